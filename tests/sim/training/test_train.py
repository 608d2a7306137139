"""End-to-end: tiny generated dataset -> train-atr -> ONNX -> detector -> eval-atr figures."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("torch", reason="torch not installed: training needs the `train` extra")

from autonomy.atr.cnn_detector import CnnDetector  # noqa: E402
from sim.evaluation.atr_metrics import evaluate_detector  # noqa: E402
from sim.dataset.generate import RenderSettings, generate_dataset  # noqa: E402
from sim.dataset.randomization import Randomization  # noqa: E402
from sim.training.train import TrainParams, train_atr  # noqa: E402

FAST = Randomization(range_max_m=(12.0, 16.0), n_targets=(1, 3), n_distractors=(0, 1), frames_per_scene=3,
                     seabed_kinds=("plane",))


@pytest.fixture(scope="module")
def tiny_dataset(tmp_path_factory):
    d = tmp_path_factory.mktemp("train") / "data"
    generate_dataset(d, 6, seed=11, workers=1, randomization=FAST,
                     settings=RenderSettings(azimuth_columns=181, elevation_rays=12), progress=False)
    return d


def test_train_export_detect_and_evaluate(tiny_dataset, tmp_path):
    out = tmp_path / "tiny.onnx"
    params = TrainParams(input_hw=(96, 176), width=8, epochs=3, batch_size=3, threads=1, max_minutes=1.0)
    summary = train_atr(tiny_dataset, out, params, log=lambda *_: None)
    assert summary["epochs_run"] == 3 and out.is_file()
    assert all(np.isfinite(h["heat"]) for h in summary["history"])
    det = CnnDetector(out, score_threshold=0.0)
    assert det.class_names == ("opi", "rock", "debris") and det.input_hw == (96, 176)
    assert det.fan_hw == (477, 894)
    meta = json.loads(det._session.get_modelmeta().custom_metadata_map["train_data"])
    assert meta["seed"] == 11 and meta["n_images"] == 6
    res = evaluate_detector(det, tiny_dataset, score_threshold=0.3)
    assert res["frames"] == 6 and res["ground_truth"] > 0
    for k in ("recall", "ap50", "ap50_95", "false_alarms_per_frame", "frames_per_s"):
        assert np.isfinite(res[k]), k
    # precision is undefined (None) exactly when the model made no detection at the threshold
    n_det = res["true_positives"] + res["false_positives"]
    assert (res["precision"] is None) == (n_det == 0) and (n_det == 0 or np.isfinite(res["precision"]))
    coco = json.loads((tiny_dataset / "annotations.json").read_text())
    with_objects = {a["image_id"] for a in coco["annotations"] if not a["iscrowd"]}
    assert summary["check"]["frames"] == len(with_objects) and not summary["check"]["held_out"]


def test_training_reduces_the_loss(tiny_dataset, tmp_path):
    # a generous time budget: the schedule then follows the steps, not the machine's speed
    params = TrainParams(input_hw=(96, 176), width=8, epochs=12, batch_size=6, lr=1e-2, threads=1, max_minutes=30.0)
    summary = train_atr(tiny_dataset, tmp_path / "m.onnx", params, log=lambda *_: None)
    heat = [h["heat"] for h in summary["history"]]
    assert heat[-1] < 0.7 * heat[0], heat  # about 0.5-0.57 of the first epoch


def test_train_on_a_folder_without_annotations_names_it(tmp_path):
    with pytest.raises(FileNotFoundError, match="annotations.json"):
        train_atr(tmp_path, tmp_path / "x.onnx", TrainParams(), log=lambda *_: None)
