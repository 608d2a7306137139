"""``auvsim sweep`` as a user meets it: a finished sweep resumed, a sweep extended, folders of
the other kind, Ctrl-C, console lines, and the names of keys and scenarios in errors."""

from __future__ import annotations

import json

import pytest

from sim.cli import main
from sim.sweep.runner import SweepSpec, run_grid, run_sweep

SMALL = ["--set", "n_lanes=2", "--set", "n_other=3", "--set", "n_particles=20", "--set", "max_tiles=3",
         "--set", "modes=[ins_filter]"]


def _sweep(tmp_path, name, *argv):
    return main(["sweep", "mcm_survey", "--out", str(tmp_path / name), "--no-progress", *SMALL, *argv])


def test_finished_sweep_resumed_with_workers_and_extended(tmp_path, capsys):
    assert _sweep(tmp_path, "s", "--runs", "2") == 0
    first = (tmp_path / "s" / "runs" / "run_00001.json").read_text()
    capsys.readouterr()
    # every run done: nothing to start, even with a process pool asked for
    assert _sweep(tmp_path, "s", "--runs", "2", "--workers", "2") == 0
    assert capsys.readouterr().out.splitlines() == [f"sweep: wrote {tmp_path / 's'} (2 runs)"]
    # more runs extend it: only run 2 is new, the old ones are kept as they were
    assert _sweep(tmp_path, "s", "--runs", "3") == 0
    lines = capsys.readouterr().out.splitlines()
    assert [json.loads(x)["run"] for x in lines[:-1]] == [2]
    assert (tmp_path / "s" / "runs" / "run_00001.json").read_text() == first
    assert json.loads((tmp_path / "s" / "summary.json").read_text())["runs"] == 3
    # fewer runs than it holds: refused, nothing removed
    assert _sweep(tmp_path, "s", "--runs", "1") == 2
    err = capsys.readouterr().err
    assert "--runs 3 or more" in err and len(err.splitlines()) == 1
    assert len(list((tmp_path / "s" / "runs").iterdir())) == 3
    # other arguments: refused, the message gives the folder's own as a command line
    assert _sweep(tmp_path, "s", "--runs", "3", "--seed", "5") == 2
    assert "--runs 3 --seed 0 --set n_lanes=2" in capsys.readouterr().err


def test_console_lines_carry_scalars_and_the_run_files_the_curves(tmp_path, capsys):
    assert _sweep(tmp_path, "s", "--runs", "1") == 0
    line = json.loads(capsys.readouterr().out.splitlines()[0])
    stored = json.loads((tmp_path / "s" / "runs" / "run_00000.json").read_text())
    assert line["ins_filter"]["final_gospa"] == stored["ins_filter"]["final_gospa"]
    assert isinstance(stored["ins_filter"]["gospa"], list) and "gospa" not in line["ins_filter"]
    assert not any(isinstance(v, list) for v in line.values())
    # the objects confirmed at the end are stored for the map: as many as the final cardinality
    spa = stored["ins_filter"]
    assert len(spa["objects_ne_m"]) == len(spa["objects_class"]) == spa["cardinality"][-1]


def test_grid_and_plain_sweep_folders_refuse_each_other(tmp_path, capsys):
    assert _sweep(tmp_path, "plain", "--runs", "1") == 0
    before = sorted(p.name for p in (tmp_path / "plain").iterdir())
    assert _sweep(tmp_path, "plain", "--runs", "1", "--grid", "pd=0.8,0.9") == 2
    assert "without --grid" in capsys.readouterr().err
    assert sorted(p.name for p in (tmp_path / "plain").iterdir()) == before
    assert _sweep(tmp_path, "grid", "--runs", "1", "--grid", "pd=0.8,0.9") == 0
    assert (tmp_path / "grid" / "grid_summary.png").stat().st_size > 0
    capsys.readouterr()
    assert _sweep(tmp_path, "grid", "--runs", "1") == 2
    assert "holds a --grid sweep" in capsys.readouterr().err
    assert not (tmp_path / "grid" / "runs").exists() and not (tmp_path / "grid" / "sweep.json").exists()


def test_interrupted_sweep_says_what_it_kept(tmp_path, capsys):
    seen = []

    def emit(line):
        seen.append(line)
        if len(seen) == 2:
            raise KeyboardInterrupt

    spec = SweepSpec("mcm_survey", runs=3, seed=0, overrides={"n_lanes": 2, "n_other": 3, "n_particles": 20,
                                                              "max_tiles": 3, "modes": ["ins_filter"]})
    with pytest.raises(KeyboardInterrupt):
        run_sweep(tmp_path / "s", spec, progress=False, emit=emit)
    assert "2 of 3 runs are kept" in capsys.readouterr().err
    assert len(list((tmp_path / "s" / "runs").iterdir())) == 2
    again = []
    run_sweep(tmp_path / "s", spec, progress=True, emit=again.append)
    assert [json.loads(x)["run"] for x in again] == [2]
    assert "2 of 3 runs already in" in capsys.readouterr().err


def test_grid_progress_names_the_point(tmp_path, capsys):
    spec = SweepSpec("mcm_survey", runs=1, seed=0, overrides={"n_lanes": 2, "n_other": 3, "n_particles": 20,
                                                              "max_tiles": 3, "modes": ["ins_filter"]})
    run_grid(tmp_path / "g", spec, {"pd": [0.8, 0.9]}, progress=True, emit=lambda _: None)
    err = capsys.readouterr().err
    assert "grid point 1/2 (pd=0.8): 1/1 runs" in err and "grid point 2/2 (pd=0.9): 1/1 runs" in err


@pytest.mark.parametrize("argv, needles", [
    (["mcm_survey", "--set", "nope=3"], ["nope", "unknown key", "n_particles"]),
    (["mcm_survey", "--set", "a.b=3"], ["a.b", "no dots"]),
    (["mcm_survey", "--set", "n_particles=abc"], ['n_particles="abc"']),
    (["mcm_survey", "--set", "modes=[]"], ["modes=[]", "at least 1"]),
    (["mcm_survey", "--grid", "pd=0.5,abc"], ["--grid", 'pd="abc"']),
    (["mcm_surevy"], ["did you mean mcm_survey?", "mcm_survey_full"]),
    (["cssn_lawnmower"], ["no Monte Carlo runner", "mcm_survey_full"]),
    (["mcm_survey_full", "--set", "n_particles=50"], ["did you mean mcm.mapper.n_particles?"]),
])
def test_bad_names_exit_2_naming_them(tmp_path, capsys, argv, needles):
    code = main(["sweep", *argv, "--runs", "1", "--out", str(tmp_path / "s"), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and len(err.splitlines()) == 1 and "Traceback" not in err
    for needle in needles:
        assert needle in err
    assert not (tmp_path / "s").exists()


@pytest.mark.parametrize("argv, needle", [
    (["run", "mcm_survey", "--out", "OUT"], "auvsim sweep mcm_survey"),
    (["validate", "mcm_survey"], "auvsim sweep mcm_survey"),
    (["run", "cssn_lawnmover", "--out", "OUT"], "did you mean cssn_lawnmower?"),
    (["bench", "mission", "--no-sonar", "--workers", "2"], "not with --no-sonar"),
])
def test_sweep_only_names_and_misspellings_elsewhere(tmp_path, capsys, argv, needle):
    argv = [str(tmp_path / "o") if a == "OUT" else a for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert needle in err and len(err.splitlines()) == 1
    assert not (tmp_path / "o").exists()


def test_scenarios_lists_the_sweep_only_study(capsys):
    assert main(["scenarios"]) == 0
    names = [line.split()[0] for line in capsys.readouterr().out.splitlines()]
    assert "mcm_survey" in names and "mcm_survey_full" in names
