"""Gym bench: the CPU-time figures that tell core contention from per-step cost."""

from __future__ import annotations

import os
import sys
import time

import pytest

from scenarios.load import load_scenario
from sim.bench import gym as gym_bench


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc/PID/stat is Linux")
def test_process_cpu_s_matches_the_os_clock():
    """/proc/PID/stat's utime + stime of this process against time.process_time (the OS's own
    per-process clock), around a busy loop of ~0.3 s."""
    c0, p0 = time.process_time(), gym_bench.process_cpu_s(os.getpid())
    x = 0
    while time.process_time() - c0 < 0.3:
        x += 1
    c1, p1 = time.process_time(), gym_bench.process_cpu_s(os.getpid())
    tick = 1.0 / os.sysconf("SC_CLK_TCK")
    assert p1 - p0 == pytest.approx(c1 - c0, abs=3 * tick)
    assert gym_bench.process_cpu_s(2**22 + 12345) is None  # no such process


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc/PID/stat is Linux")
def test_gym_bench_reports_cpu_figures():
    r = gym_bench.run(load_scenario("cssn_lawnmower"), waypoint_steps=40, survey_steps=4, sonar_steps=2, workers=2,
                      profile=False)
    for key in ("waypoint", "survey", "survey_sonar"):
        single, vec = r[key], r["vector"][key]
        assert single["cpu_ms_per_step"] > 0.0
        assert vec["n_envs"] == 2 and vec["speedup"] > 0.0
        assert vec["cpu_ms_per_step"] >= 0.0 and vec["worker_busy_fraction"] >= 0.0
    # a worker's sonar step costs about what the single env's does: n_envs by CPU time (loose:
    # 10 ms clock ticks over ~0.1 s of CPU per worker; the other variants run too few steps)
    sonar = r["vector"]["survey_sonar"]
    assert 0.8 < sonar["cpu_speedup"] < 4.0
    assert sonar["worker_busy_fraction"] <= 1.3  # one thread a worker (CPU clock ticks of 10 ms)
    assert r["load_avg_1min"] is None or r["load_avg_1min"] >= 0.0
