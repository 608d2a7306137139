"""The tracking benchmark reports wall-clock and thread-CPU tick times (docs/studies/tracking.md:
the CPU figures are the tracker's own cost, the wall-clock p99 includes the scheduler's)."""

from __future__ import annotations

from sim.bench.tracking import run


def test_tracking_bench_short_track_reports_both_clocks():
    r = run(seed=0, duration_s=20.0)
    assert r["ticks"] == 201
    for clock in ("", "cpu_"):
        assert 0.0 < r[f"{clock}p50_ms"] <= r[f"{clock}p99_ms"] <= r[f"{clock}max_ms"]
    assert r["usbl_used_in_history"] >= 1 and r["sonar_used_in_history"] >= 1
