"""``auvsim bench mission`` options: without sonar, serial against pipelined, bad options."""

from __future__ import annotations

import pytest

from scenarios import load_scenario
from sim.bench import mission as bench_mission
from sim.cli import main


def test_no_sonar_and_workers_report_both_loops_of_one_run():
    r = bench_mission.run(load_scenario("cssn_lawnmower"), sim_time_s=2.0, warmup_s=1.0, sonar=False, workers=2)
    assert r["sonar"] is False and r["fls_frames"] == 0 and r["fls_rate_hz"] == 0.0
    assert "sensor:fls" not in r["stage_ms_per_sim_s"] and "sensor:imu" in r["stage_ms_per_sim_s"]
    w = r["workers"]
    assert w["workers"] == 2 and w["pipelined"] is False  # nothing to pipeline without a sonar
    assert w["serial_real_time_factor"] == r["real_time_factor"]
    assert w["workers_speedup"] == pytest.approx(w["real_time_factor"] / r["real_time_factor"])
    assert r["cpu_real_time_factor"] > 0
    assert list(w["cpu_s_by_process"]) == ["mission"]  # no worker processes
    assert w["cores_bound_speedup"] > 0


@pytest.mark.parametrize("argv, says", [
    (["bench", "physics", "--workers", "2"], "--workers: only for bench mission, gym, dataset, vector, not physics"),
    (["bench", "pmha", "--no-sonar"], "--no-sonar: only for bench mission, not pmha"),
    (["bench", "mission", "--workers", "0"], "--workers: must be a whole number >= 1"),
])
def test_bench_options_where_they_do_not_apply_are_one_line_and_exit_2(argv, says, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert says in err and "Traceback" not in err
