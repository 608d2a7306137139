"""Dataset generator: determinism, COCO validity (boxes match masks), YOLO labels, resume."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from pycocotools.coco import COCO

from sim.dataset import generate as gen
from sim.dataset.generate import RenderSettings, generate_dataset
from sim.dataset.randomization import Randomization

# Small, fast scenes: short range window, few objects, always at least one target.
FAST = Randomization(range_max_m=(12.0, 16.0), n_targets=(1, 2), n_distractors=(0, 1), frames_per_scene=2,
                     seabed_kinds=("plane", "ripple"))
SETTINGS = RenderSettings(azimuth_columns=181, elevation_rays=12)


def _files(d: Path) -> dict[str, bytes]:
    return {str(p.relative_to(d)): p.read_bytes() for p in sorted(d.rglob("*")) if p.is_file()}


def _make(d: Path, n: int = 4, seed: int = 3, workers_override: int = 1, **kw) -> Path:
    generate_dataset(d, n, seed=seed, workers=workers_override, randomization=FAST, settings=SETTINGS, progress=False,
                     **kw)
    return d


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    return _make(tmp_path_factory.mktemp("ds") / "a")


def test_same_seed_same_files_other_seed_other_images(dataset, tmp_path):
    again = _make(tmp_path / "b")
    assert _files(dataset) == _files(again)
    other = _make(tmp_path / "c", seed=4)
    assert _files(dataset)["images/000001.png"] != _files(other)["images/000001.png"]


def test_coco_loads_and_boxes_match_masks(dataset):
    coco = COCO(str(dataset / "annotations.json"))
    anns = coco.loadAnns(coco.getAnnIds())
    assert len(coco.getImgIds()) == 4 and anns
    assert {c["name"] for c in coco.loadCats(coco.getCatIds())} == {"opi", "rock", "debris"}
    import cv2

    for a in anns:
        m = coco.annToMask(a).astype(bool)
        ys, xs = np.nonzero(m)
        # COCO box = tight box of the mask pixels, pixel i spanning [i, i + 1)
        np.testing.assert_allclose(a["bbox"], [xs.min(), ys.min(), xs.max() - xs.min() + 1, ys.max() - ys.min() + 1])
        assert a["area"] == m.sum()
        img_rec = coco.loadImgs(a["image_id"])[0]
        assert m.shape == (img_rec["height"], img_rec["width"])
    # visible targets are brighter than the image as a whole (the mask is where their echoes are)
    for a in anns:
        if a["iscrowd"] or not a["attributes"]["is_target"]:
            continue
        img = cv2.imread(str(dataset / coco.loadImgs(a["image_id"])[0]["file_name"]), cv2.IMREAD_GRAYSCALE)
        m = coco.annToMask(a).astype(bool)
        lit = img[img > 0]
        assert img[m].mean() > np.median(lit)


def test_yolo_labels_match_coco(dataset):
    coco = json.loads((dataset / "annotations.json").read_text())
    for im in coco["images"]:
        anns = [a for a in coco["annotations"] if a["image_id"] == im["id"] and not a["iscrowd"]]
        lines = (dataset / "labels" / f"{im['id']:06d}.txt").read_text().split()
        rows = np.array(lines, dtype=float).reshape(-1, 5)
        assert len(rows) == len(anns)
        for row, a in zip(rows, anns):
            x, y, w, h = a["bbox"]
            assert int(row[0]) == a["category_id"] - 1
            np.testing.assert_allclose(row[1:], [(x + w / 2) / im["width"], (y + h / 2) / im["height"],
                                                 w / im["width"], h / im["height"]], atol=1e-6)


def test_ground_truth_range_and_fan_geometry_agree(dataset):
    from autonomy.sonar_geometry import FanGeometry

    coco = json.loads((dataset / "annotations.json").read_text())
    for a in coco["annotations"]:
        im = next(i for i in coco["images"] if i["id"] == a["image_id"])
        g = im["fan_geometry"]
        geom = FanGeometry(g["width_px"], g["height_px"], g["range_min_m"], g["range_max_m"], g["fov_rad"],
                           g["m_per_px"], g["apex_x_px"], g["apex_y_px"])
        x, y, w, h = a["bbox"]
        r_box, az_box = geom.pixel_to_polar(x + w / 2 - 0.5, y + h / 2 - 0.5)
        # the echo box lies near the object's true (slant) range and bearing
        assert abs(r_box - a["attributes"]["range_m"]) < 2.0
        assert abs(az_box - a["attributes"]["azimuth_rad"]) < 0.15


def test_interrupted_run_resumes_to_the_same_dataset(dataset, tmp_path, monkeypatch):
    real = gen.render_scene

    def flaky(spec, *args, **kw):
        if spec.index == 1:
            raise KeyboardInterrupt
        return real(spec, *args, **kw)

    monkeypatch.setattr(gen, "render_scene", flaky)
    with pytest.raises(KeyboardInterrupt):
        _make(tmp_path / "r")
    man = json.loads((tmp_path / "r" / "manifest.json").read_text())
    assert man["complete"] is False and not (tmp_path / "r" / "annotations.json").exists()
    assert (tmp_path / "r" / "parts" / "scene_00000.json").exists()
    monkeypatch.setattr(gen, "render_scene", real)
    _make(tmp_path / "r")
    assert _files(tmp_path / "r") == _files(dataset)


def test_other_parameters_in_same_directory_are_refused(dataset, tmp_path):
    d = _make(tmp_path / "m", n=2)
    with pytest.raises(ValueError, match="other parameters.*seed"):
        _make(d, n=2, seed=99)


def test_a_dataset_grows_to_a_larger_n_into_the_same_files_and_is_not_cut(dataset, tmp_path):
    d = _make(tmp_path / "g", n=3)  # two frames a scene: the second scene cut at one frame
    _make(d, n=4)
    grown, whole = _files(d), _files(dataset)
    for f in (grown, whole):
        f.pop(".auvsim-output")  # the output marker lists what the folder held when it was written
    assert grown == whole  # as if made with --n 4 at once
    with pytest.raises(ValueError, match="--n 2: below the 4 frames"):
        _make(d, n=2)


def test_manifest_records_version_seed_and_parameters(dataset):
    man = json.loads((dataset / "manifest.json").read_text())
    assert man["complete"] is True and man["seed"] == 3 and man["generator_version"] == gen.GENERATOR_VERSION
    assert Randomization.model_validate(man["randomization"]) == FAST


def test_ray_missing_gives_install_hint(tmp_path, monkeypatch):
    import builtins

    real_import = builtins.__import__

    def no_ray(name, *a, **kw):
        if name == "ray":
            raise ImportError("No module named 'ray'")
        return real_import(name, *a, **kw)

    monkeypatch.setattr(builtins, "__import__", no_ray)
    with pytest.raises(ImportError, match=r"auvsim\[scale\]"):
        _make(tmp_path / "ray", n=2, use_ray=True)


RAY_CHILD = """
import sys
from pathlib import Path
from sim.dataset.generate import RenderSettings, generate_dataset
from sim.dataset.randomization import Randomization
fast = Randomization(range_max_m=(12.0, 16.0), n_targets=(1, 2), n_distractors=(0, 1), frames_per_scene=2,
                     seabed_kinds=("plane", "ripple"))
generate_dataset(Path(sys.argv[1]), 4, seed=3, workers=1, randomization=fast,
                 settings=RenderSettings(azimuth_columns=181, elevation_rays=12), progress=False, use_ray=True)
"""


def test_ray_local_instance(tmp_path, dataset):
    """Ray in a child process: its threads outlive ray.shutdown(), and a later test that forks
    this process (the dataset and sweep workers) could inherit a lock one of them held."""
    import subprocess
    import sys

    pytest.importorskip("ray", reason="ray not installed (the `scale` extra)")
    d = tmp_path / "rayds"
    r = subprocess.run([sys.executable, "-c", RAY_CHILD, str(d)], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    assert _files(d) == _files(dataset)


def test_bad_randomization_is_named():
    with pytest.raises(ValueError, match="altitude_m"):
        Randomization(altitude_m=(5.0, 2.0))
    with pytest.raises(ValueError, match="seabed_kinds"):
        Randomization(seabed_kinds=("plane", "lava"))


def test_two_workers_write_the_same_files_and_end_quietly(tmp_path, capfd):
    """Three scenes on two workers (on Linux the parent renders the first, then forks workers that
    take the others): the same files as one worker. A SIGTERM handler that raises (``auvsim``'s)
    is not inherited by the workers: the pool's shutdown ends them without a traceback."""
    import signal

    class Stop(BaseException):
        pass

    def raising(signum, frame):
        raise Stop()

    previous = signal.signal(signal.SIGTERM, raising)
    try:
        many = _make(tmp_path / "two", n=6, workers_override=2)
    finally:
        signal.signal(signal.SIGTERM, previous)
    one = _make(tmp_path / "one", n=6)
    assert _files(many) == _files(one) and len(list((one / "images").glob("*.png"))) == 6
    assert "Traceback" not in capfd.readouterr().err


def test_pool_order_puts_terrain_mesh_scenes_first_from_the_first_draws_alone():
    """The pool's expensive-first order reads each scene's seabed kind from its first two draws,
    the ones ``sample_scene`` makes: it agrees with the sampled scenes."""
    from sim.dataset.randomization import TRAIN_RANDOMIZATION

    rz_json = TRAIN_RANDOMIZATION.model_dump_json()
    kinds = [gen.scene_spec(5, i, TRAIN_RANDOMIZATION).seabed.kind for i in range(12)]
    assert {"rough", "ripple"} & set(kinds) and {"plane", "slope"} & set(kinds)
    predicted = [gen._builds_terrain_mesh((5, i, rz_json, RenderSettings())) for i in range(12)]
    assert predicted == [k in ("rough", "ripple") for k in kinds]


def _sigint_self_then_pid(_: int) -> int:
    """A pool task: Ctrl-C to its own process (as the terminal sends to the whole group), then
    its process id (a worker that did not ignore it would raise instead and die)."""
    import os
    import signal
    import time

    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(0.05)  # the signal is handled at the next bytecode: let it land here
    return os.getpid()


@pytest.mark.parametrize("start_method", ["fork", "spawn"])
def test_pool_workers_ignore_ctrl_c_and_a_ctrl_c_while_they_start_ends_the_pool(start_method):
    """Ctrl-C reaches the workers too; they ignore it (the parent ends the pool), so none prints
    a traceback. A Ctrl-C that arrives while the pool starts is held back until the pool is
    built, then raised in the parent, and the workers end with the pool."""
    import multiprocessing as mp
    import os
    import signal
    import threading

    if start_method not in mp.get_all_start_methods():
        pytest.skip(f"no {start_method} start here")
    mask_before = signal.pthread_sigmask(signal.SIG_BLOCK, set())
    with gen._worker_pool(start_method, 2) as pool:
        pids = pool.map_async(_sigint_self_then_pid, range(4), chunksize=1).get(timeout=60)
    assert len(pids) == 4 and os.getpid() not in pids
    assert signal.pthread_sigmask(signal.SIG_BLOCK, set()) == mask_before

    workers, blocked_at_start = [], []
    real_pool = mp.context.BaseContext.Pool

    def pool_then_ctrl_c(self, *args, **kwargs):
        blocked_at_start.append(signal.SIGINT in signal.pthread_sigmask(signal.SIG_BLOCK, set()))
        p = real_pool(self, *args, **kwargs)
        workers.extend(p._pool)
        signal.pthread_kill(threading.get_ident(), signal.SIGINT)  # held while this thread blocks it
        return p

    mp.context.BaseContext.Pool = pool_then_ctrl_c
    try:
        with pytest.raises(KeyboardInterrupt):
            with gen._worker_pool(start_method, 2):
                pytest.fail("the held-back Ctrl-C must end the block before its body")
    finally:
        mp.context.BaseContext.Pool = real_pool
    assert blocked_at_start == [True] and len(workers) == 2
    for w in workers:
        w.join(timeout=10)
        assert not w.is_alive()
    assert signal.pthread_sigmask(signal.SIG_BLOCK, set()) == mask_before


UNGUARDED_SPAWN = """
import sim.dataset.generate as gen
gen.sys = type("Platform", (), {"platform": "darwin"})()  # the spawn path (macOS, Windows)
gen.generate_dataset(OUT, 8, workers=2, progress=False)
"""


def test_spawned_workers_from_a_script_without_the_main_guard_give_one_clear_error(tmp_path):
    """Where workers are spawned, an unguarded script would re-run itself in each worker (an
    endless respawn, hundreds of tracebacks): one probe process finds it out and the call raises
    DatasetError saying what to do; nothing is rendered."""
    import subprocess
    import sys

    script = tmp_path / "unguarded.py"
    script.write_text(f"OUT = {str(tmp_path / 'ds')!r}\n" + UNGUARDED_SPAWN)
    root = Path(__file__).resolve().parents[3]
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120,
                         cwd=tmp_path, env={**__import__("os").environ, "PYTHONPATH": str(root)})
    assert out.returncode == 1
    assert out.stderr.count("Traceback") == 1, out.stderr[-2000:]
    assert 'DatasetError: workers=2: the worker processes start with spawn here' in out.stderr
    assert 'if __name__ == "__main__":' in out.stderr.splitlines()[-1]
    assert not list((tmp_path / "ds" / "images").glob("*.png"))
