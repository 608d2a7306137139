"""Bad input gets one clear line naming the culprit, exit status 2, no traceback, and
nothing outside the output folder changes (sentinel files all around it)."""

from __future__ import annotations

import hashlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from sim.cli import main
from tests.support import assert_clean_error, run_cli

SHORT_RUN = ["--set", "duration_s=4", "--no-rerun", "--detector", "none", "--quiet"]


def _snapshot(root: Path) -> dict[str, str]:
    """Every file and folder below ``root`` -> content hash (folders: 'dir')."""
    out = {}
    for p in sorted(root.rglob("*")):
        rel = str(p.relative_to(root))
        out[rel] = "dir" if p.is_dir() else hashlib.sha256(p.read_bytes()).hexdigest()
    return out


@pytest.fixture
def sandbox(tmp_path, monkeypatch):
    """A working folder with sentinel files next to, above and below where outputs go."""
    work = tmp_path / "work"
    (work / "src").mkdir(parents=True)
    (work / "keep.txt").write_text("x")
    (work / "src" / "module.py").write_text("print('hi')\n")
    (tmp_path / "sibling.txt").write_text("y")
    (work / "a_file").write_text("not a folder")
    monkeypatch.chdir(work)
    return tmp_path


@pytest.mark.parametrize("out", [".", "", "..", "~", "/"])
def test_out_that_would_lose_data_is_refused(sandbox, capsys, out):
    before = _snapshot(sandbox)
    code, err = run_cli(["run", "--out", out, "--overwrite", *SHORT_RUN], capsys)
    assert_clean_error(code, err, "--out")
    assert "refusing" in err or "empty string" in err
    assert _snapshot(sandbox) == before


def test_out_that_contains_the_working_directory_is_refused(sandbox, capsys):
    before = _snapshot(sandbox)
    code, err = run_cli(["run", "--out", str(sandbox), "--overwrite", *SHORT_RUN], capsys)
    assert_clean_error(code, err, "contains the current directory")
    assert _snapshot(sandbox) == before


@pytest.mark.parametrize("out,why", [("a_file", "is a file"), ("/proc/x", "cannot create"),
                                     ("src", "not an auvsim run output")])
def test_out_that_cannot_be_written_is_named(sandbox, capsys, out, why):
    before = _snapshot(sandbox)
    code, err = run_cli(["run", "--out", out, "--overwrite", *SHORT_RUN], capsys)
    assert_clean_error(code, err, "--out", why)
    assert _snapshot(sandbox) == before


def test_overwrite_replaces_only_an_earlier_run_and_only_when_complete(sandbox, capsys):
    assert main(["run", "--out", "runs/a", *SHORT_RUN]) == 0
    first = (sandbox / "work/runs/a/metrics.json").read_text()
    assert (sandbox / "work/runs/a/.auvsim-output").is_file()
    code, err = run_cli(["run", "--out", "runs/a", *SHORT_RUN], capsys)
    assert_clean_error(code, err, "--overwrite")
    assert (sandbox / "work/runs/a/metrics.json").read_text() == first
    assert main(["run", "--out", "runs/a", "--overwrite", "--seed", "5", *SHORT_RUN]) == 0
    assert '"seed": 5' in (sandbox / "work/runs/a/metrics.json").read_text()
    leftovers = [p.name for p in (sandbox / "work/runs").iterdir()]
    assert leftovers == ["a"], leftovers
    assert (sandbox / "work/keep.txt").read_text() == "x"


def test_a_failed_run_keeps_the_earlier_one(sandbox, capsys, monkeypatch):
    assert main(["run", "--out", "runs/a", *SHORT_RUN]) == 0
    before = _snapshot(sandbox)
    import sim.mission.run as mo

    def broken(*a, **k):
        raise RuntimeError("plot failed")

    monkeypatch.setattr(mo, "plot_map", broken)
    code = main(["run", "--out", "runs/a", "--overwrite", *SHORT_RUN])
    assert code == 1
    assert _snapshot(sandbox) == before  # the earlier run is intact, no partial folder left


@pytest.mark.parametrize("content,why", [(b"\x00\x01binary", "binary"), (b"", "empty"),
                                         (b"\xff\xfe name: x", "UTF-8"), (b"a: [1, 2", "not valid YAML")])
def test_bad_scenario_files(sandbox, capsys, content, why):
    path = sandbox / "work" / "bad.yaml"
    path.write_bytes(content)
    code, err = run_cli(["run", str(path), "--out", "runs/x", *SHORT_RUN], capsys)
    assert_clean_error(code, err, "bad.yaml", why)
    assert not (sandbox / "work/runs").exists()


def test_scenario_that_is_a_directory(sandbox, capsys):
    code, err = run_cli(["validate", str(sandbox / "work" / "src")], capsys)
    assert_clean_error(code, err, "src", "is a directory")


@pytest.mark.parametrize("override,named", [
    ("vehicle.initial_pos_ned=[.nan, 0, 0.3]", "vehicle.initial_pos_ned.0"),
    ("world.current.velocity_ned_mps=[.inf, 0, 0]", "world.current.velocity_ned_mps.0"),
    ("world.targets.0.pos_ned=[.nan, 10, 4]", "world.targets.0.pos_ned.0"),
    ("vehicle.initial_pos_ned=[1e12, 0, 0.3]", "outside the seabed patch"),
    ("vehicle.initial_pos_ned=[30, 0, 0.3]", "outside the basin walls"),
    ("vehicle.initial_pos_ned=[8, 0, 3.9]", "into the seabed"),
    ("world.targets.0.pos_ned=[0, 10, -1]", "above the surface"),
    ("world.targets.0.pos_ned=[0, 10, 7]", "buried below the seabed"),
    ("world.targets.1.pos_ned=[0, 10.4, 4]", "overlap"),
    ("world.targets.9.radius_m=1", "has 6 entries"),
    ("world.targets.x.radius_m=1", "index 0 to 5"),
    ("seed=-1", "seed"),
    ("autonomy.atr.model_path=/no/such/model.onnx", "autonomy.atr.model_path"),
    ("nokey", "key.path=value"),
])
def test_values_that_would_break_the_run_are_rejected_at_load(capsys, override, named):
    code, err = run_cli(["validate", "cssn_lawnmower", "--set", override], capsys)
    assert_clean_error(code, err, named, "--set")


def test_corrupt_model_is_named_by_its_key(sandbox, capsys):
    bad = sandbox / "work" / "corrupt.onnx"
    bad.write_bytes(b"not a protobuf at all")
    code, err = run_cli(["validate", "cssn_lawnmower", "--set", f"autonomy.atr.model_path={bad}"], capsys)
    assert_clean_error(code, err, "autonomy.atr.model_path", "corrupt.onnx", "not a valid ONNX model")


def test_shipped_scenarios_pass_the_placement_checks(capsys):
    from scenarios.load import list_scenarios

    for name in list_scenarios():
        assert main(["validate", name]) == 0, capsys.readouterr().err


@pytest.mark.parametrize("argv,named", [
    (["eval-atr", "--data", "/no/such/folder"], "--data"),
    (["eval-atr", "--data", "."], "annotations.json"),
    (["eval-atr", "--model", "/no/such.onnx", "--data", "."], "--model"),
    (["eval-atr", "--threshold", "5"], "--threshold"),
    (["eval-atr", "--max-images", "0"], "--max-images"),
    (["dataset", "--n", "0", "--out", "ds"], "--n"),
    (["dataset", "--n", "-5", "--out", "ds"], "--n"),
    (["dataset", "--n", "2", "--out", "a_file"], "is a file"),
    (["dataset", "--n", "2", "--out", "/proc/x"], "cannot create"),
    (["dataset", "--n", "2", "--out", "."], "current directory"),
    (["dataset", "--n", "2", "--out", "src"], "not an auvsim dataset"),
    (["train-atr", "--data", "/no/such/folder", "--out", "m.onnx"], "--data"),
    (["train-atr", "--data", "src", "--out", "m.onnx"], "annotations.json"),
    (["train-atr", "--data", "d", "--out", "m.onnx", "--input", "100x200"], "--input"),
    (["run", "--seed", "-3", "--out", "r"], "--seed"),
    (["bench", "nothing"], "invalid choice"),
])
def test_command_arguments(sandbox, capsys, argv, named):
    before = _snapshot(sandbox)
    code, err = run_cli(argv, capsys)
    assert_clean_error(code, err, named)
    assert _snapshot(sandbox) == before


def test_train_atr_without_torch_says_how_to_install(sandbox):
    code = ("import sys, importlib.abc\n"
            "class NoTorch(importlib.abc.MetaPathFinder):\n"
            "    def find_spec(self, name, path, target=None):\n"
            "        if name.split('.')[0] == 'torch':\n"
            "            raise ImportError('No module named torch')\n"
            "sys.meta_path.insert(0, NoTorch())\n"
            "from sim.cli import main\n"
            "sys.exit(main(['train-atr', '--data', 'x', '--out', 'm.onnx']))\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=sandbox / "work")
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    assert "pip install 'auvsim[train]'" in proc.stderr


def test_aborted_mission_says_so_and_exits_3(sandbox, capsys):
    # the mission clock runs out mid-survey (a survey shorter than 8 s would have finished)
    code = main(["run", "--out", "runs/ab", "--set", "duration_s=15", "--set", "autonomy.guidance.mission.start_delay_s=0",
                 "--set", "autonomy.guidance.mission.max_mission_time_s=8", "--no-rerun", "--detector", "none",
                 "--quiet"])
    captured = capsys.readouterr()
    assert code == 3
    assert "ABORTED: mission time" in captured.err
    assert (sandbox / "work/runs/ab/metrics.json").is_file()


@pytest.mark.parametrize("scenario,overrides,named", [
    # 0.2 m altitude: under min_altitude_m 0.5, and 3.8 m deep over the 4 m bed, under safe_depth_max_m 3.5
    ("cssn_lawnmower", ["autonomy.guidance.survey.altitude_m=0.2"],
     ["autonomy.guidance.survey.altitude_m (0.2 m)", "autonomy.guidance.mission.min_altitude_m (0.5 m)",
      "3.80 m deep", "autonomy.guidance.mission.safe_depth_max_m (3.5 m)"]),
    ("cssn_lawnmower", ["autonomy.guidance.mission.safe_depth_max_m=1.0"],
     ["autonomy.guidance.survey.altitude_m (2 m)", "2.00 m deep", "autonomy.guidance.mission.safe_depth_max_m (1 m)"]),
    ("cssn_lawnmower", ["autonomy.guidance.mission.safe_depth_min_m=2.5"],
     ["autonomy.guidance.mission.safe_depth_min_m (2.5 m)"]),
    ("tank_rectangular", ["autonomy.guidance.mission.safe_depth_max_m=1.0"],  # depth mode, 2 m
     ["autonomy.guidance.survey.depth_m (2 m)", "autonomy.guidance.mission.safe_depth_max_m (1 m)"]),
    ("pool_circular", ["autonomy.guidance.mission.min_altitude_m=1.6"],  # 1.5 m deep over a 3 m bed
     ["autonomy.guidance.survey.depth_m (1.5 m)", "1.50 m above", "autonomy.guidance.mission.min_altitude_m (1.6 m)"]),
    ("cssn_lawnmower", ["vehicle.initial_pos_ned=[8, 0, 3.0]", "autonomy.guidance.mission.safe_depth_max_m=2.5",
                        "autonomy.guidance.survey.altitude_m=2.0"],
     ["vehicle.initial_pos_ned", "start depth 3 m", "safe_depth_max_m (2.5 m)"]),
])
def test_a_survey_past_the_abort_limits_is_refused_at_load(sandbox, capsys, scenario, overrides, named):
    """What would abort (exit 3) once the survey gets there is refused before anything runs or
    is written, in one line per setting naming the survey key and the limits it breaks."""
    sets = [a for o in overrides for a in ("--set", o)]
    for argv in (["validate", scenario, *sets], ["run", scenario, "--out", "runs/lim", *sets, *SHORT_RUN[2:]]):
        before = _snapshot(sandbox)
        code, err = run_cli(argv, capsys)
        assert_clean_error(code, err, *named, "--set")
        assert "would abort" in err
        assert _snapshot(sandbox) == before


def test_a_survey_at_its_limits_still_runs(capsys):
    """Equal values are allowed: altitude_m at min_altitude_m, the survey depth at safe_depth_max_m."""
    assert main(["validate", "cssn_lawnmower", "--set", "autonomy.guidance.survey.altitude_m=0.5",
                 "--set", "autonomy.guidance.mission.safe_depth_max_m=3.5"]) == 0, capsys.readouterr().err


def test_console_summary_is_rounded_and_says_n_a(sandbox, capsys):
    assert main(["run", "--out", "runs/s", *SHORT_RUN]) == 0
    out = capsys.readouterr().out
    assert "nan" not in out
    assert "mean error n/a" in out  # no detector: nothing matched
    import json

    metrics = json.loads((sandbox / "work/runs/s/metrics.json").read_text())
    assert metrics["sim_time_s"] == 4.0
    assert "world_model.json holds all" in metrics["world_model"]["note"]


def test_progress_without_a_terminal_is_a_line_every_few_percent(sandbox):
    proc = subprocess.run([sys.executable, "-m", "sim.cli", "run", "--out", "runs/p", "--set", "duration_s=30",
                           "--no-rerun", "--detector", "none"], capture_output=True, text=True,
                          cwd=sandbox / "work")
    assert proc.returncode == 0, proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if "% of the planned" in ln]
    assert 1 <= len(lines) <= 11, proc.stderr


def test_sigint_leaves_no_partial_folder(sandbox):
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, "-m", "sim.cli", "run", "--out", "runs/i", "--set", "duration_s=600",
                             "--no-rerun", "--detector", "none"], cwd=sandbox / "work", env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            # a background job may inherit SIGINT ignored; the user's shell would not
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    partial = sandbox / "work/runs/.i.partial"
    deadline = time.monotonic() + 60
    while not partial.exists() and time.monotonic() < deadline:
        time.sleep(0.1)
    assert partial.exists(), "the run never started"
    time.sleep(1.0)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    assert not partial.exists()
    assert not (sandbox / "work/runs/i").exists()


def test_overwrite_refuses_a_run_folder_holding_the_users_own_files(sandbox, capsys):
    assert main(["run", "--out", "runs/k", *SHORT_RUN]) == 0
    (sandbox / "work/runs/k/notes.txt").write_text("mine")
    (sandbox / "work/runs/k/analysis").mkdir()
    before = _snapshot(sandbox)
    code, err = run_cli(["run", "--out", "runs/k", "--overwrite", *SHORT_RUN], capsys)
    assert_clean_error(code, err, "notes.txt", "analysis", "did not write")
    assert _snapshot(sandbox) == before


@pytest.mark.parametrize("override,named", [
    ("duration_s=true", "duration_s"),
    ("seed='3'", "seed"),
    ("autonomy.guidance.survey.origin_ne_m=[200, 200]", "past the seabed patch"),
    ("autonomy.guidance.survey.origin_ne_m=[30, 0]", "past the basin walls"),
    ("autonomy.guidance.survey.altitude_m=10", "autonomy.guidance.survey.altitude_m"),
])
def test_types_and_surveys_that_cannot_be_are_rejected(capsys, override, named):
    code, err = run_cli(["validate", "cssn_lawnmower", "--set", override], capsys)
    assert_clean_error(code, err, named, "--set")


def test_scientific_notation_without_a_dot_is_a_number(capsys):
    assert main(["validate", "cssn_lawnmower", "--set", "duration_s=5e2"]) == 0
    assert "duration_s: 500.0" in capsys.readouterr().out


def test_a_key_given_twice_is_an_error(sandbox, capsys):
    path = sandbox / "work" / "dup.yaml"
    path.write_text("duration_s: 900\nduration_s: 5\n")
    code, err = run_cli(["validate", str(path)], capsys)
    assert_clean_error(code, err, "dup.yaml", "'duration_s' appears twice")


def _tiny_dataset_copy(sandbox, name: str) -> Path:
    folder = sandbox / "work" / name
    (folder / "images").mkdir(parents=True)
    return folder


@pytest.mark.parametrize("content,why", [("{bad", "not a readable COCO JSON"), ("", "not a readable COCO JSON"),
                                         ("{}", "missing images"), ("[]", "missing images")])
def test_corrupt_dataset_annotations_are_named(sandbox, capsys, content, why):
    folder = _tiny_dataset_copy(sandbox, "ds")
    (folder / "annotations.json").write_text(content)
    code, err = run_cli(["eval-atr", "--data", str(folder), "--detector", "classical"], capsys)
    assert_clean_error(code, err, "annotations.json", why)


def test_damaged_manifest_on_resume_is_named(sandbox, capsys):
    folder = _tiny_dataset_copy(sandbox, "ds")
    (folder / "manifest.json").write_text("{bad")
    (folder / ".auvsim-output").write_text('{"kind": "dataset"}')
    code, err = run_cli(["dataset", "--n", "2", "--out", str(folder), "--workers", "1", "--no-progress"], capsys)
    assert_clean_error(code, err, "manifest.json", "damaged")


@pytest.mark.parametrize("argv,named", [
    (["dataset", "--n", "99999999999", "--out", "ds"], "--n"),
    (["dataset", "--n", "2", "--out", "ds", "--heldout", "--randomization", "wide"], "contradict"),
    (["eval-atr", "--detector", "classical", "--model", "m.onnx"], "--model applies to the cnn detector"),
    (["eval-atr", "--model", "src"], "is a folder"),
    (["bench", "atr", "--model", "src"], "is a folder"),
    (["bench", "export", "--scenario", "pool_circular"], "does not fly a scenario of yours"),
    (["run", "--out", "x", "--bogus"], "auvsim run: error: unrecognized arguments"),
])
def test_contradictions_and_limits(sandbox, capsys, argv, named):
    before = _snapshot(sandbox)
    code, err = run_cli(argv, capsys)
    assert_clean_error(code, err, named)
    assert _snapshot(sandbox) == before


def test_a_full_disk_is_reported_as_such_not_as_a_bug(sandbox, capsys, monkeypatch):
    import errno

    import sim.mission.run as mo

    def full(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device", "runs/f/.partial/trajectory.csv")

    monkeypatch.setattr(mo.TrajectoryLog, "write_csv", full)
    code, err = run_cli(["run", "--out", "runs/f", *SHORT_RUN], capsys)
    assert_clean_error(code, err, "No space left on device")
    assert not (sandbox / "work/runs/f").exists() and not (sandbox / "work/runs/.f.partial").exists()


def test_a_closed_pipe_ends_quietly(sandbox):
    proc = subprocess.run(f"{sys.executable} -m sim.cli validate cssn_lawnmower | head -1", shell=True,
                          capture_output=True, text=True, cwd=sandbox / "work")
    assert "Traceback" not in proc.stderr and "internal error" not in proc.stderr, proc.stderr


def test_the_entry_point_loads_nothing_heavy_before_its_interrupt_guard():
    proc = subprocess.run([sys.executable, "-c", "import sys, sim.cli; print('numpy' in sys.modules)"],
                          capture_output=True, text=True)
    assert proc.stdout.strip() == "False", proc.stderr


def test_a_run_stopped_by_its_duration_says_so(sandbox, capsys):
    assert main(["run", "--out", "runs/d", *SHORT_RUN]) == 0
    assert "NOT FINISHED: the run reached duration_s = 4 s" in capsys.readouterr().err


def test_dataset_ray_without_ray_fails_first_and_creates_nothing(sandbox):
    """Without Ray, ``--ray`` is one line naming it and how to install it, exit 2, before any
    progress bar or output folder."""
    code = ("import sys, importlib.abc\n"
            "class NoRay(importlib.abc.MetaPathFinder):\n"
            "    def find_spec(self, name, path, target=None):\n"
            "        if name.split('.')[0] == 'ray':\n"
            "            raise ImportError('No module named ray')\n"
            "sys.meta_path.insert(0, NoRay())\n"
            "from sim.cli import main\n"
            "sys.exit(main(['dataset', '--n', '2', '--out', 'runs/ds', '--ray']))\n")
    before = _snapshot(sandbox)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=sandbox / "work")
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr  # no progress bar drawn first
    assert lines[0].startswith("auvsim dataset: error: --ray") and "pip install" in lines[0]
    assert _snapshot(sandbox) == before
    assert not (sandbox / "work/runs").exists()


def test_version_prints_the_package_version(capsys):
    from importlib.metadata import version

    assert main(["--version"]) == 0
    out = capsys.readouterr().out
    assert out.strip() == f"auvsim {version('auvsim')}"


def test_render_fls_example_needs_out_and_leaves_the_docs_figure_alone(capsys):
    import importlib.util

    root = Path(__file__).resolve().parents[2]
    figure = root / "docs" / "fls_frame.png"
    before = hashlib.sha256(figure.read_bytes()).hexdigest(), figure.stat().st_mtime_ns
    spec = importlib.util.spec_from_file_location("render_fls_example", root / "scripts" / "render_fls_example.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    capsys.readouterr()
    assert mod.main([]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "render_fls_example.py: error:" in err[0] and "--out" in err[0], err
    assert (hashlib.sha256(figure.read_bytes()).hexdigest(), figure.stat().st_mtime_ns) == before


@pytest.mark.parametrize("args, flag", [(["--detector", "none"], "(from --detector none)"),
                                        (["--set", "autonomy.atr.detector=none"], "(from --set autonomy.atr.detector=none)")])
def test_an_error_names_the_option_that_set_the_value(sandbox, capsys, args, flag):
    code, err = run_cli(["run", "cssn_inspect", "--out", "runs/insp", *args], capsys)
    assert_clean_error(code, err, flag)
    assert len(err.strip().splitlines()) == 1
    assert not (sandbox / "runs" / "insp").exists()
