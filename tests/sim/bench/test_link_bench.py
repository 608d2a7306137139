"""The link benchmark runs, accounts for every message and times in microseconds."""

from __future__ import annotations

from sim.bench import BENCHES
from sim.bench.link import _auv_track, measure

import numpy as np


def test_bench_small_case():
    r = measure(duration_s=300.0, repeats=1)
    assert r["link_sent"] == r["messages_sent"] > 100
    assert r["link_sent"] == r["link_delivered"] + r["link_lost"] + r["link_pending"]
    # 20-40 m apart, both ends under way at 0.5 m/s: channel loss 1 - 0.98 * 0.975^2 = 6.8 %
    n = r["link_sent"] - r["link_pending"]
    p = 1 - 0.98 * 0.975**2
    assert abs(r["link_lost_channel"] - n * p) <= 4 * np.sqrt(n * p * (1 - p))
    # latency: a 32-37 byte packet plus 16 bytes of framing at 1000 bit/s, tens of metres
    assert 0.38 < r["link_mean_latency_s"] < r["link_p95_latency_s"] < 2.0
    assert 0.0 < r["link_us_per_tick_idle"] < 1000.0 and r["encode_us_per_message"] < 1000.0
    assert "link" in BENCHES


def test_track_is_a_lawnmower_at_the_survey_speed():
    t = np.arange(0.0, 2000.0, 0.1)
    p = _auv_track(t)
    step = np.linalg.norm(np.diff(p, axis=0), axis=1)
    assert np.allclose(step, 0.05, atol=1e-9)
    assert p[:, 1].min() == 0.0 and p[:, 1].max() == 200.0
