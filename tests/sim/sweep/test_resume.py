"""``auvsim sweep``: resumable, same summary after an interruption, bad input exits 2."""

from __future__ import annotations

import json

import pytest

from sim.cli import main
from sim.sweep.runner import SweepError, SweepSpec, run_sweep

SMALL = {"n_lanes": 2, "n_other": 4, "n_particles": 40, "max_tiles": 6, "modes": ["spa", "ins_filter"]}


def _summary(folder):
    s = json.loads((folder / "summary.json").read_text())
    s.pop("wall_s_this_call")
    return s


def test_interrupted_sweep_resumes_to_the_same_summary(tmp_path):
    spec = SweepSpec("mcm_survey", runs=3, seed=7, overrides=SMALL)
    lines = []
    run_sweep(tmp_path / "a", spec, progress=False, emit=lines.append)
    assert len(lines) == 3 and {json.loads(x)["run"] for x in lines} == {0, 1, 2}
    full = _summary(tmp_path / "a")
    # an interrupted sweep: run 1 never finished, no summary yet
    (tmp_path / "a" / "runs" / "run_00001.json").unlink()
    (tmp_path / "a" / "summary.json").unlink()
    again = []
    run_sweep(tmp_path / "a", spec, progress=False, emit=again.append)
    assert [json.loads(x)["run"] for x in again] == [1]  # finished runs are not redone
    assert _summary(tmp_path / "a") == full
    for name in ("gospa.png", "cardinality.png", "detections_vs_false.png", "results.jsonl"):
        assert (tmp_path / "a" / name).stat().st_size > 0
    with pytest.raises(Exception, match="other arguments"):
        run_sweep(tmp_path / "a", SweepSpec("mcm_survey", runs=3, seed=8, overrides=SMALL), progress=False,
                  emit=lambda _: None)


@pytest.mark.parametrize("argv, needle", [
    (["--set", "pd=-0.5"], "pd"),
    (["--set", "tile_length_m=5000", "--set", "n_lanes=1", "--set", "area_side_m=100"], "longer than the survey"),
])
def test_bad_input_exits_2(tmp_path, capsys, argv, needle):
    code = main(["sweep", "mcm_survey", "--runs", "1", "--out", str(tmp_path / "s"), "--no-progress", *argv])
    assert code == 2
    assert needle in capsys.readouterr().err
    assert not (tmp_path / "s").exists()


def test_ray_address_that_does_not_answer_exits_2(tmp_path):
    """In a child process: Ray's client threads must not live on in the test process, which
    later tests fork."""
    import socket
    import subprocess
    import sys

    pytest.importorskip("ray", reason="ray not installed (the `scale` extra)")
    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    port = sock.getsockname()[1]
    sock.close()  # a free port: nothing listens there
    r = subprocess.run([sys.executable, "-m", "sim.cli", "sweep", "mcm_survey", "--runs", "1", "--out",
                        str(tmp_path / "s"), "--no-progress", "--ray", f"127.0.0.1:{port}"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 2 and "no Ray cluster answers" in r.stderr, r.stderr[-2000:]
    assert not (tmp_path / "s").exists()


def test_unknown_scenario_is_a_sweep_error(tmp_path):
    with pytest.raises(SweepError, match="sweepable"):
        run_sweep(tmp_path / "x", SweepSpec("nope", 1, 0, {}), progress=False)
