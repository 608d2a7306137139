"""A full-mode run too short to form a side-scan tile: ``auvsim run`` keeps its other outputs
and says to raise ``duration_s``; ``auvsim sweep`` refuses it as bad input (exit 2, one line)."""

from __future__ import annotations

import json

from sim.cli import main


def test_run_too_short_for_a_tile_still_writes_its_outputs(tmp_path, capsys):
    code = main(["run", "mcm_survey_full", "--out", str(tmp_path / "r"), "--no-rerun", "--quiet",
                 "--set", "duration_s=4"])
    out = capsys.readouterr().out
    assert code == 0
    metrics = json.loads((tmp_path / "r" / "metrics.json").read_text())
    assert metrics["mcm"]["tiles"] == 0 and "raise duration_s" in metrics["mcm"]["note"]
    assert "no side-scan tile" in out and (tmp_path / "r" / "map.png").is_file()


def test_sweep_too_short_for_a_tile_exits_2_and_takes_new_arguments(tmp_path, capsys):
    argv = ["sweep", "mcm_survey_full", "--runs", "1", "--out", str(tmp_path / "s"), "--no-progress"]
    assert main([*argv, "--set", "duration_s=4"]) == 2
    err = capsys.readouterr().err
    assert "duration_s" in err and "Traceback" not in err
    assert "resumes" not in err  # the same command would fail the same way
    # no run finished there, so the folder takes other arguments (a bad first try is not a trap)
    assert main([*argv, "--set", "duration_s=5"]) == 2
    assert "other arguments" not in capsys.readouterr().err
