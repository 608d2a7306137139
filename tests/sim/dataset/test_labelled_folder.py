"""Labelled folders of real frames (the watertank layout) read as COCO, scored with pycocotools
per class, and refused in one line when damaged; the project's own datasets still read the same."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from autonomy.atr.detector import to_detections
from sim.dataset.errors import DatasetError
from sim.dataset.labelled_folder import load_labelled_folder
from sim.evaluation.atr_metrics import evaluate_detector
from tests.support import REAL_WATERTANK_DIR as REAL
from tests.support import (
    WATERTANK_GEOM,
    assert_clean_error,
    run_cli,
    watertank_box_xml,
    write_fan_dataset,
    write_watertank_folder,
)

FRAMES = [
    [("Bottle", (120, 200, 30, 14)), ("Tire", (170, 300, 40, 40))],
    [("Can", (140, 250, 16, 16)), ("Wall", (60, 120, 200, 20))],
    [("Bottle", (100, 330, 28, 12)), ("Can", (200, 220, 14, 15))],
    [("Tire", (150, 180, 42, 38))],
    [],
    [("Chain", (130, 260, 50, 10)), ("Wall", (70, 110, 180, 25))],
]


class _Oracle:
    """Returns each frame's labelled boxes (found by the frame's image), optionally leaving out
    classes or shifting every box; scores fall with the box index."""

    def __init__(self, folder, drop=(), shift_px=0.0) -> None:
        self.by_image = {}
        self.class_names = tuple(folder.class_names)
        for rec in folder.coco["images"]:
            anns = [a for a in folder.coco["annotations"] if a["image_id"] == rec["id"]]
            names = {c["id"]: c["name"] for c in folder.coco["categories"]}
            self.by_image[folder.image(rec).tobytes()] = [(names[a["category_id"]], a["bbox"]) for a in anns]
        self.drop, self.shift = set(drop), shift_px

    def detect(self, frame, score_threshold=0.5):
        boxes = [(c, b) for c, b in self.by_image[frame.fan.tobytes()] if c not in self.drop]
        xyxy = np.array([[x - 0.5 + self.shift, y - 0.5, x + w - 0.5 + self.shift, y + h - 0.5]
                         for _, (x, y, w, h) in boxes]).reshape(-1, 4)
        scores = np.linspace(0.9, 0.6, len(boxes))
        return to_detections(frame, xyxy, scores, [c for c, _ in boxes])


def test_a_watertank_folder_reads_as_coco_with_its_fan_fitted(tmp_path):
    root = write_watertank_folder(tmp_path / "tank", FRAMES)
    f = load_labelled_folder(root)
    assert f.layout == "watertank"
    assert [im["file_name"] for im in f.coco["images"]] == [f"images/frame-{i}.png" for i in range(len(FRAMES))]
    assert "Wall" not in f.target_classes and len(f.target_classes) == 10
    names = {c["id"]: c["name"] for c in f.coco["categories"]}
    got = [(a["image_id"], names[a["category_id"]], a["bbox"]) for a in f.coco["annotations"]]
    want = [(i + 1, c, list(b)) for i, boxes in enumerate(FRAMES) for c, b in boxes]
    assert got == want
    g = f.coco["images"][0]["fan_geometry"]
    # the fitted fan is the drawn one: apex, half-angle, and the metric scale of a 0.7 m window
    assert g["apex_x_px"] == pytest.approx(WATERTANK_GEOM.apex_x_px, abs=0.7)
    assert g["apex_y_px"] == pytest.approx(WATERTANK_GEOM.apex_y_px, abs=3.0)
    assert math.degrees(g["fov_rad"]) == pytest.approx(30.0, abs=0.3)
    assert g["m_per_px"] == pytest.approx(WATERTANK_GEOM.m_per_px, rel=0.02)
    assert g["range_max_m"] == pytest.approx(2.9, rel=0.02)
    a = f.coco["annotations"][0]  # range of the box centre from the apex
    x, y, w, h = a["bbox"]
    r = math.hypot(x + w / 2 - 0.5 - WATERTANK_GEOM.apex_x_px, y + h / 2 - 0.5 - WATERTANK_GEOM.apex_y_px) * 0.005
    assert a["attributes"]["range_m"] == pytest.approx(r, rel=0.02)


def test_per_class_ap_from_pycocotools_on_known_detections(tmp_path):
    f = load_labelled_folder(write_watertank_folder(tmp_path / "tank", FRAMES))
    perfect = evaluate_detector(_Oracle(f), f.root, 0.5)
    assert perfect["layout"] == "watertank" and perfect["frames"] == len(FRAMES)
    present = {"Bottle", "Can", "Tire", "Chain"}
    assert {c for c, v in perfect["ap50_by_class"].items() if v is not None} == present  # the others: no truth
    assert all(perfect["ap50_by_class"][c] == pytest.approx(1.0) for c in present)
    assert perfect["map50"] == pytest.approx(1.0) and perfect["map50_95"] == pytest.approx(1.0)
    assert perfect["ap50_scored_apart"] == {"Wall": pytest.approx(1.0)}
    assert perfect["precision"] == 1.0 and perfect["recall"] == 1.0 and perfect["ground_truth"] == 7  # no wall
    # range bands of the tank's window (2.9 m): four of 0.8 m, every object in one of them
    assert [b["range_m"] for b in perfect["by_range_band"]] == [[0.0, 0.8], [0.8, 1.6], [1.6, 2.4], [2.4, None]]
    assert sum(b["ground_truth"] for b in perfect["by_range_band"]) == 7
    # one class never detected: its AP is 0 and the mean is over the four classes with truth
    no_can = evaluate_detector(_Oracle(f, drop={"Can"}), f.root, 0.5)
    assert no_can["ap50_by_class"]["Can"] == 0.0
    assert no_can["map50"] == pytest.approx(3 / 4)
    assert no_can["recall"] == pytest.approx(5 / 7)
    # the PR curves at IoU 0.5: precision 1 at every recall point for a class found whole,
    # 0 throughout for the class never detected; only when asked for
    assert "pr50_by_class" not in no_can
    curves = evaluate_detector(_Oracle(f, drop={"Can"}), f.root, 0.5, pr_curves=True)["pr50_by_class"]
    assert curves["Tire"] == [1.0] * 101 and curves["Can"] == [0.0] * 101
    assert set(curves) == set(no_can["ap50_by_class"])
    # the wall missed changes nothing of the objects' figures
    no_wall = evaluate_detector(_Oracle(f, drop={"Wall"}), f.root, 0.5)
    assert no_wall["map50"] == pytest.approx(1.0) and no_wall["ap50_scored_apart"]["Wall"] == 0.0
    # boxes shifted by 10 px: the narrow boxes fall below IoU 0.5, the wide ones stay above
    shifted = evaluate_detector(_Oracle(f, shift_px=10.0), f.root, 0.5)
    assert shifted["ap50_by_class"]["Tire"] == pytest.approx(1.0)  # 40 px wide: IoU 0.6
    assert shifted["ap50_by_class"]["Can"] == 0.0  # 14-16 px: IoU < 0.3
    assert shifted["map50_95"] < shifted["map50"] < 1.0


def test_the_projects_own_datasets_still_score_opi(tmp_path):
    root = write_fan_dataset(tmp_path / "ds", n_images=3)
    f = load_labelled_folder(root)
    assert f.layout == "coco" and f.target_classes == ("opi",)


@pytest.mark.parametrize("boxes, culprit", [
    ('<annotation><object><name>Boat</name><bndbox><x>1</x><y>1</y><w>5</w><h>5</h></bndbox></object>'
     '</annotation>', "class 'Boat'"),
    (watertank_box_xml([("Can", (300, 470, 40, 40))]), "outside the 320 x 480 px image"),
    ("<annotation><object><name>Can</name></object>", "frame-1.xml"),
])
def test_damaged_labels_are_refused_naming_the_file(tmp_path, boxes, culprit):
    root = write_watertank_folder(tmp_path / "tank", FRAMES[:3])
    (root / "boxes" / "frame-1.xml").write_text(boxes)
    with pytest.raises(DatasetError, match="frame-1.xml") as exc:
        load_labelled_folder(root)
    assert culprit.replace("'", "") in str(exc.value).replace("'", "") and "\n" not in str(exc.value)


def test_eval_atr_refuses_what_it_cannot_score_in_one_line(tmp_path, capsys):
    root = write_watertank_folder(tmp_path / "tank", FRAMES)
    code, err = run_cli(["eval-atr", "--data", str(root)], capsys)
    assert_clean_error(code, err, "320 x 480", "894 x 477")  # the shipped model's fan is another sonar's
    code, err = run_cli(["eval-atr", "--data", str(root), "--detector", "classical"], capsys)
    assert_clean_error(code, err, "classes (opi)", "Bottle")
    code, err = run_cli(["eval-atr", "--data", str(root), "--model", "no_such_model"], capsys)
    assert_clean_error(code, err, "--model no_such_model", "shipped: atr_centernet")
    code, err = run_cli(["eval-atr", "--data", str(root), "--model", "atr_centernet"], capsys)  # a shipped name
    assert_clean_error(code, err, "894 x 477")
    (tmp_path / "half" / "images").mkdir(parents=True)
    code, err = run_cli(["eval-atr", "--data", str(tmp_path / "half")], capsys)
    assert_clean_error(code, err, "--data", "has images/ but neither boxes/")


def test_training_reads_the_watertank_layout(tmp_path):
    from sim.training.data import labelled_class_counts, load_detection_arrays

    root = write_watertank_folder(tmp_path / "tank", FRAMES)
    counts = labelled_class_counts(root)
    assert counts["Bottle"] == 2 and counts["Wall"] == 2 and counts["Hook"] == 0
    arrays = load_detection_arrays(root, (480, 320), input_transform="pad")
    assert arrays.images.shape == (len(FRAMES), 480, 320) and arrays.fan_hw == (480, 320)
    np.testing.assert_allclose(arrays.boxes[0][0], [119.5, 199.5, 149.5, 213.5])  # (x, y, w, h) -> xyxy


def test_the_real_development_split_reads_as_labelled_frames():
    if not REAL.is_dir():
        pytest.skip(f"real frames not here ({REAL}): the shared Marine Debris development split is absent")
    f = load_labelled_folder(REAL)
    assert len(f.coco["images"]) == 600
    counts = {}
    for a in f.coco["annotations"]:
        counts[a["category_id"]] = counts.get(a["category_id"], 0) + 1
    assert set(counts) == set(range(1, 12))  # every class, the wall too
    fans = {json.dumps(im["fan_geometry"], sort_keys=True) for im in f.coco["images"]}
    assert len(fans) == 2  # the split's two recordings
    assert all(0.7 <= a["attributes"]["range_m"] <= 3.5 for a in f.coco["annotations"])


def test_the_shipped_synthetic_debris_model_names_the_marine_debris_classes():
    from autonomy.atr.build import resolve_model, shipped_model_names
    from autonomy.atr.cnn_detector import CnnDetector
    from sim.dataset.real_frames import MARINE_DEBRIS_CLASSES

    assert "marine_debris_synthetic" in shipped_model_names()
    det = CnnDetector(resolve_model("marine_debris_synthetic"))
    assert list(det.class_names) == [MARINE_DEBRIS_CLASSES[k] for k in sorted(MARINE_DEBRIS_CLASSES)]
