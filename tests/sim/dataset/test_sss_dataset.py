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
from sim.scene.target_meshes import target_mesh

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


# The CLI's side-scan tiles (default settings: 40 m range, 500 bins a side) over the flat seabed
# where a low altitude blacks out most: 30 m tiles, two per scene, three or four targets each.
RZ_FLAT = Randomization(seabed_kinds=("plane",), n_targets=(3, 4), n_distractors=(0, 0), burial_probability=0.0,
                        altitude_m=(1.5, 6.0))  # the FLS altitudes, which a side-scan does not use
S_CLI = SssSettings(line_length_m=60.0, tile_length_m=30.0)


@pytest.fixture(scope="module")
def cli_tiles(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("sss_cli") / "ds"
    generate_dataset(d, 4, seed=2, workers=1, randomization=RZ_FLAT, settings=S_CLI, progress=False)
    return d


def test_the_manifest_records_the_side_scan_randomisation(cli_tiles):
    """Side-scan altitudes are 10-20 % of the 40 m range (4-8 m), not the FLS ranges' 1.5-6 m,
    and no FLS-only range (tilt, range window, frames per scene) is recorded."""
    rz = json.loads((cli_tiles / "manifest.json").read_text())["randomization"]
    assert rz["altitude_m"] == pytest.approx([4.0, 8.0])
    assert rz["seabed_depth_m"][0] >= 8.0 + 2.0  # the transducer stays 2 m deep at 8 m altitude
    for fls_only in ("tilt_deg", "range_min_m", "range_max_m", "frames_per_scene", "vertical_beamwidth_deg",
                     "step_m"):
        assert fls_only not in rz
    alts = [im["sonar"]["altitude_m"] for im in json.loads((cli_tiles / "annotations.json").read_text())["images"]]
    assert all(4.0 <= a <= 8.0 for a in alts)


def _shadow_behind(img: np.ndarray, bbox, n_bins: int, window_px: int) -> bool:
    """The ``window_px`` bins just beyond a box in slant range (its pings) are shadow: their
    median at most 0.35 of the insonified seabed just before it (itself at least 8 counts)."""
    x, y, w, h = (int(round(v)) for v in bbox)
    rows = img[y:y + max(h, 1)].astype(float)
    if x + w <= n_bins:  # port: far range at column 0
        beyond, near = rows[:, max(x - window_px, 0):x], rows[:, x + w:min(x + w + window_px, n_bins)]
    else:  # starboard: far range at the last column
        beyond, near = rows[:, x + w:x + w + window_px], rows[:, max(x - window_px, n_bins):x]
    if beyond.size == 0 or near.size == 0:
        return False
    level = float(np.median(near))
    return level >= 8.0 and float(np.median(beyond)) <= 0.35 * level


def test_tiles_show_the_seabed_and_far_targets_cast_shadows(cli_tiles):
    """Black (a 9 x 9 mean under 2 counts) is little more than the nadir gap, the water column
    of one altitude (10-20 % of each side); most targets in the far half of the swath show a
    shadow behind them, the side-scan's main cue."""
    import cv2

    coco = json.loads((cli_tiles / "annotations.json").read_text())
    ims = {im["id"]: im for im in coco["images"]}
    tiles = {i: cv2.imread(str(cli_tiles / im["file_name"]), cv2.IMREAD_GRAYSCALE) for i, im in ims.items()}
    for i, img in tiles.items():
        nadir = ims[i]["sonar"]["altitude_m"] / S_CLI.range_max_m
        black = float(np.mean(cv2.blur(img.astype(np.float32), (9, 9)) < 2.0))
        assert black <= nadir + 0.1, (i, black, nadir)
    far = []
    for a in coco["annotations"]:
        if not a["attributes"]["is_target"]:
            continue
        g = ims[a["image_id"]]["sss_geometry"]
        slant_m = abs(a["bbox"][0] + 0.5 * a["bbox"][2] - g["n_bins"]) * g["bin_size_m"]
        if slant_m > 0.5 * S_CLI.range_max_m:
            far.append(_shadow_behind(tiles[a["image_id"]], a["bbox"], g["n_bins"], int(round(1.0 / g["bin_size_m"]))))
    assert len(far) >= 5
    assert np.mean(far) >= 0.6, far
