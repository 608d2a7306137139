"""``auvsim sweep --grid``: one resumable sub-sweep per grid point, one JSON line per run."""

from __future__ import annotations

import json

import pytest

from sim.cli import main
from sim.sweep.runner import SweepError, SweepSpec, grid_points, parse_grid, run_grid

SMALL = {"n_lanes": 2, "n_other": 3, "max_tiles": 4, "modes": ["ins_filter"]}


def test_grid_parsing_and_points(tmp_path):
    g = parse_grid(["n_particles=20,40", "pd=0.8,0.9,1.0"])
    assert g == {"n_particles": [20, 40], "pd": [0.8, 0.9, 1.0]}
    pts = grid_points(g)
    assert len(pts) == 6 and pts[0] == {"n_particles": 20, "pd": 0.8} and pts[-1] == {"n_particles": 40, "pd": 1.0}
    f = tmp_path / "g.yaml"
    f.write_text("n_particles: [20, 40]\n")
    assert parse_grid([str(f)]) == {"n_particles": [20, 40]}
    for bad in (["n_particles"], ["n_particles="], ["pd=0.8", "pd=0.9"]):
        with pytest.raises(SweepError):
            parse_grid(bad)


def test_grid_runs_every_point_and_resumes(tmp_path):
    spec = SweepSpec("mcm_survey", runs=2, seed=3, overrides=SMALL)
    lines = []
    out = run_grid(tmp_path / "g", spec, {"n_particles": [20, 30]}, progress=False, emit=lines.append)
    assert out["runs"] == 4 and len(lines) == 4
    assert sorted((json.loads(x)["grid_point"]["n_particles"], json.loads(x)["run"]) for x in lines) == [
        (20, 0), (20, 1), (30, 0), (30, 1)]
    summary = json.loads((tmp_path / "g" / "grid_summary.json").read_text())
    assert [p["point"] for p in summary["points"]] == [{"n_particles": 20}, {"n_particles": 30}]
    (tmp_path / "g" / "n_particles=30" / "runs" / "run_00001.json").unlink()
    again = []
    run_grid(tmp_path / "g", spec, {"n_particles": [20, 30]}, progress=False, emit=again.append)
    assert [(json.loads(x)["grid_point"], json.loads(x)["run"]) for x in again] == [({"n_particles": 30}, 1)]


def test_bad_grid_point_exits_2_before_running(tmp_path, capsys):
    code = main(["sweep", "mcm_survey", "--runs", "1", "--out", str(tmp_path / "s"), "--no-progress",
                 "--grid", "pd=0.9,-0.5"])
    assert code == 2
    assert "pd" in capsys.readouterr().err
    assert not (tmp_path / "s").exists()
