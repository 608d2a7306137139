"""``auvsim run --workers N`` on a mission the pipeline does not take says so (same results)."""

from __future__ import annotations

from sim.cli import main


def test_workers_on_a_mission_without_fls_perception_says_the_loop_is_serial(tmp_path, capsys):
    code = main(["run", "pool_circular", "--out", str(tmp_path / "r"), "--workers", "2", "--no-rerun", "--quiet",
                 "--set", "duration_s=1"])
    assert code == 0
    assert "--workers 2: this mission runs the serial loop" in capsys.readouterr().err
