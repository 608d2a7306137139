"""The study scripts (``scripts/tracking_study.py``, ``scripts/evaluate_msis_localization.py``,
``scripts/evaluate_sea_trial.py``)
refuse bad input as the CLI does: one line naming the argument, exit status 2, no traceback,
before any run (so a study's results are never lost at its end)."""

from __future__ import annotations


import json
from pathlib import Path

import numpy as np
import pytest
from tests.support import SCRIPTS, load_script, script_refusal


@pytest.mark.parametrize("argv,culprits", [
    (["--seeds", "0"], ("tracking_study.py: error:", "--seeds", ">= 1")),
    (["--duration", "-5"], ("--duration", "> 0")),
    (["--duration", "nan"], ("--duration",)),
    (["--scenarios", "track_static_vehicel"], ("track_static_vehicel", "no such scenario")),
    (["--scenarios", "pool_circular"], ("--scenarios pool_circular", "does not track a target")),
    (["--scenarios", "track_static_vehicle", "--png", "{file}"], ("--png", "is a file")),
    (["--scenarios", "track_static_vehicle", "--json", "{missing}/x.json"], ("--json", "does not exist")),
    (["--scenarios", "track_static_vehicle", "--json", "{dir}"], ("--json", "is a folder")),
])
def test_tracking_study_refuses(argv, culprits, capsys, tmp_path):
    (tmp_path / "f.txt").write_text("keep")
    argv = [a.format(file=tmp_path / "f.txt", missing=tmp_path / "nope", dir=tmp_path) for a in argv]
    script_refusal(load_script("tracking_study"), argv, capsys, *culprits)
    assert (tmp_path / "f.txt").read_text() == "keep"


@pytest.mark.parametrize("argv,culprits", [
    (["pool_circular", "--seeds", "0"], ("evaluate_msis_localization.py: error:", "--seeds")),
    (["pool_circuler"], ("pool_circuler", "no such scenario")),
    (["cssn_lawnmower"], ("cssn_lawnmower", "no enabled msis sensor")),
    (["pool_circular", "--set", "sensors.msis.rang_m=3"], ("sensors.msis.rang_m", "did you mean range_m?")),
    (["pool_circular", "--set", "sensors.msis.sector_width_grad=401"], ("sector_width_grad", "400")),
])
def test_msis_evaluation_refuses(argv, culprits, capsys):
    script_refusal(load_script("evaluate_msis_localization"), argv, capsys, *culprits)


@pytest.mark.parametrize("argv,culprits", [
    (["--seeds", "a,b"], ("evaluate_sea_trial.py: error:", "--seeds 'a,b'", "comma list")),
    (["--seeds", "5-2"], ("--seeds '5-2'",)),
    (["--seeds", "1", "--workers", "3"], ("--workers 3", "1 or 2")),
    (["--seeds", "1", "--scenario", "cssn_sea_tral"], ("cssn_sea_tral", "did you mean cssn_sea_trial?")),
    (["--seeds", "1", "--scenario", "cssn_lawnmower"], ("--scenario cssn_lawnmower", "comms.acoustic.enabled")),
    (["--seeds", "1", "--set", "nope=1"], ("nope", "unknown key")),
    (["--seeds", "1", "--out", "{file}"], ("--out", "is a file")),
])
def test_sea_trial_evaluation_refuses(argv, culprits, capsys, tmp_path):
    (tmp_path / "f.txt").write_text("keep")
    argv = [a.format(file=tmp_path / "f.txt") for a in argv]
    if "--out" not in argv:
        argv += ["--out", str(tmp_path / "out")]
    script_refusal(load_script("evaluate_sea_trial"), argv, capsys, *culprits)
    assert (tmp_path / "f.txt").read_text() == "keep"
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("argv,culprits", [
    ([], ("atr_detect_ab.py: error:", "--other")),
    (["--other", "{missing}"], ("--other", "no autonomy/atr/cnn_detector.py")),
    (["--other", "{root}", "--sim-s", "-3"], ("--sim-s", "> 0")),
    (["--other", "{root}", "--sim-s", "nan"], ("--sim-s",)),
    (["--other", "{root}", "--scenario", "cssn_lawnmowr", "--sim-s", "1"], ("cssn_lawnmowr", "no such scenario")),
])
def test_atr_detect_ab_refuses(argv, culprits, capsys, tmp_path):
    argv = [a.format(missing=tmp_path / "nope", root=SCRIPTS.parent) for a in argv]
    script_refusal(load_script("atr_detect_ab"), argv, capsys, *culprits)


@pytest.mark.parametrize("argv,culprits", [
    (["--bench-frames", "0"], ("fls_frame_digest.py: error:", "--bench-frames", ">= 1")),
    (["--dataset-frames", "0"], ("--dataset-frames", ">= 1")),
    (["--scenes", "x"], ("--scenes", "'x'")),
    (["--scenario", "cssn_lawnmowr"], ("cssn_lawnmowr", "no such scenario")),
])
def test_fls_frame_digest_refuses(argv, culprits, capsys):
    from sim.sensors.fls import FlsSensor

    render = FlsSensor.render
    script_refusal(load_script("fls_frame_digest"), argv, capsys, *culprits)
    assert FlsSensor.render is render  # its digest hook does not outlive the call


@pytest.mark.parametrize("argv,culprits", [
    (["--duration-s", "0", "--out", "{png}"], ("xtf_waterfall.py: error:", "--duration-s")),
    (["--scenario", "mcm_survey_ful", "--out", "{png}"], ("mcm_survey_ful", "did you mean mcm_survey_full?")),
    (["--scenario", "cssn_lawnmower", "--out", "{png}"], ("--scenario cssn_lawnmower", "sss")),
    (["--out", "{dir}"], ("--out", "png")),
    (["--out", "{dir}/sub.png/"], ("--out",)),
    (["--out", "{missing}/x.png"], ("--out", "does not exist")),
    (["--out", "{dir}/x.txt"], ("--out", ".png")),
    ([], ("--out",)),
])
def test_xtf_waterfall_refuses(argv, culprits, capsys, tmp_path):
    (tmp_path / "sub.png").mkdir()
    argv = [a.format(missing=tmp_path / "nope", dir=tmp_path, png=tmp_path / "f.png") for a in argv]
    script_refusal(load_script("xtf_waterfall"), argv, capsys, *culprits)


@pytest.mark.parametrize("make,culprits", [
    (lambda d: d / "nope", ("no such file or folder",)),
    (lambda d: (d / "run" / "rosbag").mkdir(parents=True) or d / "run", ("a run folder", "rosbag")),
    (lambda d: (d / "b").mkdir() or d / "b", ("one .mcap file, found 0",)),
    (lambda d: [(d / "c").mkdir(), (d / "c" / "x.mcap").write_bytes(b"not an mcap file")] and d / "c",
     ("not a readable MCAP file",)),
])
def test_check_bag_readers_refuses(make, culprits, capsys, tmp_path):
    pytest.importorskip("mcap")
    pytest.importorskip("rosbags")
    script_refusal(load_script("check_bag_readers"), [str(make(tmp_path))], capsys, "check_bag_readers.py: error:",
                   *culprits)


@pytest.mark.parametrize("argv,culprits", [
    (["--data", "{tank}", "--out", "{dir}/page.txt"], ("dataset_preview:", "--out", ".png")),
    (["--data", "{tank}", "--out", "{dir}/nope/page.png"], ("--out", "does not exist")),
    (["--data", "{tank}", "--out", "{dir}/page.png", "--frames", "0"], ("--frames 0", "1 to 64")),
    (["--data", "{dir}/empty", "--out", "{dir}/page.png"], ("--data", "no such folder")),
])
def test_dataset_preview_refuses_and_draws(argv, culprits, capsys, tmp_path):
    from tests.support import write_watertank_folder

    tank = write_watertank_folder(tmp_path / "tank", [[("Bottle", (120, 200, 30, 14))], [("Tire", (150, 250, 40, 40))]])
    mod = load_script("dataset_preview")
    argv = [a.format(tank=tank, dir=tmp_path) for a in argv]
    assert mod.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and all(c in err for c in culprits), err
    assert mod.main(["--data", str(tank), "--out", str(tmp_path / "ok.png"), "--frames", "2"]) == 0
    import cv2

    page = cv2.imread(str(tmp_path / "ok.png"))
    assert page.shape == (480, 640, 3)
    assert (page[200:215, 119:151] == (80, 220, 80)).all(axis=-1).any()  # the first class's box drawn


def test_split_labelled_folder_splits_by_links_and_refuses_bad_input(capsys, tmp_path):
    from sim.dataset.labelled_folder import load_labelled_folder
    from tests.support import write_watertank_folder

    frames = [[("Bottle", (120, 200 + 10 * i, 30, 14))] for i in range(6)]
    tank = write_watertank_folder(tmp_path / "tank", frames)
    mod = load_script("split_labelled_folder")
    out = str(tmp_path / "s")
    script_refusal(mod, ["--data", str(tank), "--train", "7", "--out", out], capsys, "--train 7", "between 1 and 5")
    script_refusal(mod, ["--data", str(tank), "--train", "2", "--out", str(tank)], capsys, "--out", "exists")
    script_refusal(mod, ["--data", str(tmp_path), "--train", "2", "--out", out], capsys, "not a watertank-layout")
    assert mod.main(["--data", str(tank), "--train", "2", "--seed", "3", "--out", str(tmp_path / "s")]) == 0
    train, rest = load_labelled_folder(tmp_path / "s" / "train"), load_labelled_folder(tmp_path / "s" / "rest")
    assert len(train.coco["images"]) == 2 and len(rest.coco["images"]) == 4
    names = lambda f: {Path(im["file_name"]).name for im in f.coco["images"]}  # noqa: E731
    assert not names(train) & names(rest) and len(names(train) | names(rest)) == 6
    assert all(p.is_symlink() for p in (tmp_path / "s" / "train" / "images").iterdir())  # nothing copied
    assert len(train.coco["annotations"]) == 2


def test_sim_to_real_runs_every_step_on_a_few_frames_and_refuses_bad_input(capsys, tmp_path):
    pytest.importorskip("torch", reason="training needs the `train` extra")
    from tests.support import write_watertank_folder

    frames = [[("Bottle", (120, 200, 30, 14)), ("Tire", (150, 300, 40, 40))] for _ in range(6)]
    real = write_watertank_folder(tmp_path / "real", frames)
    mod = load_script("sim_to_real")
    script_refusal(mod, ["--real", str(real), "--out", str(tmp_path / "o"), "--few", "5", "--most", "3"], capsys,
                   "--few 5", "below --most 3")
    script_refusal(mod, ["--real", str(tmp_path), "--out", str(tmp_path / "o")], capsys, "--real")
    # bad values are refused in --smoke too (not replaced), and a refused run leaves no folder
    script_refusal(mod, ["--real", str(real), "--out", str(tmp_path / "o"), "--smoke", "--splits", "0"], capsys,
                   "--splits 0")
    script_refusal(mod, ["--real", str(real), "--out", str(tmp_path / "o"), "--few", "3", "--most", "6"], capsys,
                   "--most 6", "below the 6 frames")
    assert not (tmp_path / "o").exists()
    assert mod.main(["--real", str(real), "--out", str(tmp_path / "s2r"), "--smoke", "--quiet"]) == 0
    res = json.loads((tmp_path / "s2r" / "sim_to_real.json").read_text())
    assert [r["model"] for r in res["rows"]] == ["synthetic", "synthetic", "real_few", "synthetic+real_few",
                                                 "synthetic", "real_most", "synthetic+real_most"]
    assert res["rows"][0]["score"]["frames"] == 6 and res["rows"][2]["score"]["frames"] == 4  # its split's rest
    assert res["training"]["synthetic+real_few"]["init_from"].endswith("synthetic.ckpt")
    assert (tmp_path / "s2r" / "real_frames_synthetic_only.png").is_file()
    assert (tmp_path / "s2r" / "sim_to_real_pr.png").is_file()
    assert res["smoke"] is True and (tmp_path / "s2r" / "sim_to_real.md").read_text().startswith("**Smoke run**")
    conf = res["confusion_synthetic_only"]["by_true_class"]  # every labelled object counted once
    assert sum(conf["Bottle"].values()) == 6 and sum(conf["Tire"].values()) == 6
    # equal optimiser steps whatever the frame count: 2 frames and 4 frames are one batch of 4 each
    assert res["training"]["real_few"]["epochs"] == res["training"]["real_most"]["epochs"] == 1
    first = (tmp_path / "s2r" / "sim_to_real.json").read_text()
    assert mod.main(["--real", str(real), "--out", str(tmp_path / "s2r"), "--smoke", "--quiet"]) == 0  # resumes: done
    assert json.loads(first)["training"] == json.loads((tmp_path / "s2r" / "sim_to_real.json").read_text())["training"]


def test_a_split_by_scene_keeps_near_copies_together(tmp_path):
    """Frames of three scenes (near-copies within a scene, distinct between them): a split by
    scene never puts one scene on both sides; the scene grouping finds the three scenes."""
    import cv2

    from sim.dataset.split import scene_groups, split_folder
    from tests.support import write_watertank_folder

    scenes = [0, 0, 0, 0, 1, 1, 2, 2, 2]
    tank = write_watertank_folder(tmp_path / "tank", [[("Bottle", (120, 200, 30, 14))] for _ in scenes])
    rng = np.random.default_rng(1)
    bases = [rng.integers(0, 255, (480, 320)).astype(float) for _ in range(3)]
    for i, s in enumerate(scenes):
        img = np.clip(bases[s] + rng.normal(0.0, 2.0, (480, 320)), 0, 255).astype(np.uint8)
        cv2.imwrite(str(tank / "images" / f"frame-{i}.png"), img)
    label = scene_groups([tank / "images" / f"frame-{i}.png" for i in range(len(scenes))])
    assert len(set(label)) == 3 and all((label[i] == label[j]) == (scenes[i] == scenes[j])
                                        for i in range(9) for j in range(9))
    for seed in range(4):
        split = split_folder(tank, 5, seed, tmp_path / f"s{seed}", by="scene")
        train_scenes = {scenes[int(n.split("-")[1])] for n in split["train"]}
        rest_scenes = {scenes[int(n.split("-")[1])] for n in split["rest"]}
        assert not train_scenes & rest_scenes and len(split["train"]) <= 5
    with pytest.raises(ValueError, match="--split-by 'time'"):
        split_folder(tank, 2, 0, tmp_path / "bad", by="time")


@pytest.mark.parametrize("argv,culprits", [
    (["--tabulate", "{runs}", "{missing}/x.json"], ("--tabulate", "x.json: cannot read it")),
    (["--tabulate", "{notruns}"], ("--tabulate", "not a file of runs")),
    (["--tabulate", "{empty}"], ("--tabulate", "not a file of runs")),
    (["--layout", "cssn", "--lawnmower-json", "{missing}/x.json"], ("--lawnmower-json", "x.json: cannot read it")),
    (["--layout", "cssn", "--json", "{missing}/x.json"], ("--json", "does not exist")),
    (["--layout", "cssn", "--json", "{dir}"], ("--json", "is a folder")),
    (["--tabulate", "{runs}", "--png", "{missing}/x.png"], ("--png", "does not exist")),
    (["--no-inspect", "--layout", "cssn"], ("--no-inspect", "--equal-time")),
    (["--layout", "mixed4"], ("mixed4", "layout of this study (cssn, mixed3, mixed8, mixed12)", "did you mean")),
    (["--seeds", "4-"], ("--seeds",)),
    (["--seeds", "5-2"], ("--seeds", "runs backwards", "2-5")),
    (["--jobs", "0"], ("--jobs", "the cores here")),
    (["--jobs", "100000"], ("--jobs", "the cores here")),
    (["--tabulate", "{notjson}"], ("--tabulate", "not JSON")),
])
def test_inspection_study_refuses(argv, culprits, capsys, tmp_path):
    """Every refusal comes before any mission flies, so no study's results are lost at its end."""
    run = {"layout": "cssn", "seed": 0, "variant": "lawnmower", "mission_time_s": 415.0}
    (tmp_path / "runs.json").write_text(json.dumps([run]))
    (tmp_path / "metrics.json").write_text(json.dumps({"inspection": {}}))
    (tmp_path / "empty.json").write_text("[]")
    (tmp_path / "study.log").write_text("cssn seed 0 lawnmower: 415 s\n")
    argv = [a.format(runs=tmp_path / "runs.json", notruns=tmp_path / "metrics.json", empty=tmp_path / "empty.json",
                     notjson=tmp_path / "study.log", missing=tmp_path / "nope", dir=tmp_path) for a in argv]
    script_refusal(load_script("inspection_study"), argv, capsys, *culprits)
