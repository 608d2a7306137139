"""The PMHA benchmark runs and its synthetic survey is solved."""

from __future__ import annotations

from sim.bench.pmha import measure


def test_bench_measure_small_case():
    r = measure(n_anchors=10, max_hypotheses=10, repeats=1)
    assert r["objects_reported"] == 10  # every object found, no false ones
    assert r["hypotheses_mean"] <= 10
    assert 0.0 < r["update_ms_p50"] <= r["update_ms_p99"]
