"""Side-scan dataset (``auvsim dataset --sensor sss``): COCO loads, boxes against the objects'
footprints computed from their true pose and the vehicle track, determinism, bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from pycocotools.coco import COCO

from autonomy.frames import rot_from_euler
from sim.cli import main
from sim.dataset.generate import generate_dataset
from sim.dataset.randomization import Randomization
from sim.dataset.sss_generate import SssSettings, sss_scene_spec
from sim.target_meshes import target_mesh

# Buried objects have a smaller exposed footprint than their mesh: none here.
RZ = Randomization(altitude_m=(2.0, 4.0), n_targets=(1, 2), n_distractors=(0, 1), seabed_kinds=("plane", "ripple"),
                   burial_probability=0.0)
# 0.4 m per ping, 8 m tiles (20 pings), 2 tiles per scene, 0.1 m slant bins
S = SssSettings(line_length_m=16.0, tile_length_m=8.0, speed_mps=2.0, range_max_m=20.0, n_bins=200,
                elevation_rays=24, rate_hz=5.0)
SEED = 5


def _files(d: Path) -> dict[str, bytes]:
    return {str(p.relative_to(d)): p.read_bytes() for p in sorted(d.rglob("*")) if p.is_file()}


def _make(d: Path, workers: int) -> Path:
    generate_dataset(d, 4, seed=SEED, workers=workers, randomization=RZ, settings=S, progress=False)
    return d


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    return _make(tmp_path_factory.mktemp("sss") / "a", 1)


def test_coco_and_yolo_load(dataset):
    coco = COCO(str(dataset / "annotations.json"))
    assert len(coco.getImgIds()) == 4
    anns = coco.loadAnns(coco.getAnnIds())
    assert len(anns) >= 3
    for im in coco.loadImgs(coco.getImgIds()):
        assert (im["height"], im["width"]) == (20, 400)
        rows = np.array((dataset / "labels" / f"{im['id']:06d}.txt").read_text().split(), dtype=float).reshape(-1, 5)
        mine = [a for a in anns if a["image_id"] == im["id"]]
        assert len(rows) == len(mine)
    assert json.loads((dataset / "manifest.json").read_text())["sensor"] == "sss"


def test_boxes_match_the_objects_footprints_from_true_geometry(dataset):
    coco = json.loads((dataset / "annotations.json").read_text())
    ims = {im["id"]: im for im in coco["images"]}
    step = S.speed_mps / S.ping_rate_hz()
    checked = 0
    for a in coco["annotations"]:
        im = ims[a["image_id"]]
        spec = sss_scene_spec(SEED, im["scene"], RZ, S)
        tgt = spec.targets[a["attributes"]["object_id"]]
        assert tgt.name == a["attributes"]["object"]
        # object mesh in NED, and the track: straight, level in heading, depth linear along it
        v = target_mesh(tgt).vertices @ rot_from_euler(*np.deg2rad(tgt.rpy_deg)).T + np.asarray(tgt.pos_ned)
        p0 = np.asarray(im["sonar"]["line_start_ned"])
        hd = np.array([np.cos(im["sonar"]["heading_rad"]), np.sin(im["sonar"]["heading_rad"])])
        along = (v[:, :2] - p0[:2]) @ hd
        across = (v[:, :2] - p0[:2]) @ np.array([-hd[1], hd[0]])  # starboard > 0
        assert np.all(across > 0) or np.all(across < 0)
        x, y, w, h = (int(b) for b in a["bbox"])
        k = im["first_ping"] + np.arange(y, y + h)  # the box's pings
        s = k * step
        # rows: only pings whose beam plane cuts the object (one ping of slack)
        assert s.min() >= along.min() - step and s.max() <= along.max() + step
        # the ping nearest the object's middle is in the box, if the tile holds it
        k_mid = int(round(0.5 * (along.min() + along.max()) / step))
        if im["first_ping"] + 1 <= k_mid < im["first_ping"] + im["height"] - 1:
            assert y - 1 <= k_mid - im["first_ping"] <= y + h
        # columns: slant ranges from those pings to the object (one bin of slack), on its side
        z = p0[2] + (im["sonar"]["end_depth_m"] - p0[2]) * s / S.line_length_m
        r = np.sqrt((along[None, :] - s[:, None]) ** 2 + across[None, :] ** 2 + (v[None, :, 2] - z[:, None]) ** 2)
        bins = np.floor(r / (S.range_max_m / S.n_bins)).astype(int)
        lo, hi = bins.min() - 1, bins.max() + 1
        cols = (S.n_bins - 1 - np.array([hi, lo])) if across[0] < 0 else (S.n_bins + np.array([lo, hi]))
        assert cols[0] <= x and x + w - 1 <= cols[1], (a, cols)
        if h >= 3:  # an object several pings long
            checked += 1
    assert checked >= 1


def test_same_files_with_one_or_two_workers(dataset, tmp_path):
    assert _files(dataset) == _files(_make(tmp_path / "b", 2))


@pytest.mark.parametrize("extra,named", [
    (["--sensor", "foo"], "--sensor"),
    (["--sensor", "sss", "--tile-length", "200", "--line-length", "100"], "--tile-length"),
    (["--tile-length", "20"], "--tile-length"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, extra, named):
    capsys.readouterr()
    code = main(["dataset", "--n", "2", "--out", str(tmp_path / "ds"), *extra])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "Traceback" not in err and len(err.splitlines()) == 1, err
    assert named in err and err.startswith("auvsim ")
    assert not (tmp_path / "ds").exists()
