"""Multi-rate scheduling: sensors fire at their rates and messages arrive after their latency."""

from __future__ import annotations

import numpy as np
import pytest

from sim.scheduler import SensorScheduler


def test_rates_and_latency_on_physics_clock():
    dt = 1.0 / 200.0
    sch = SensorScheduler(eps_s=0.25 * dt)
    sch.add("imu", 100.0, 0.0)
    sch.add("dvl", 5.0, 0.1)
    sch.add("fls", 3.0, 0.2)
    fired = {"imu": [], "dvl": [], "fls": []}
    delivered = []
    for k in range(1, 2001):  # 10 s
        t = k * dt
        for name in sch.due(t):
            fired[name].append(t)
            sch.push(name, t, (name, t))
        for name, (n2, t_fire) in sch.pop_ready(t):
            delivered.append((name, t_fire, t))
    assert len(fired["imu"]) == pytest.approx(1000, abs=1)
    assert len(fired["dvl"]) == pytest.approx(50, abs=1)
    assert len(fired["fls"]) == pytest.approx(30, abs=1)
    assert np.allclose(np.diff(fired["fls"]), 1 / 3, atol=dt)
    lat = {"imu": 0.0, "dvl": 0.1, "fls": 0.2}
    for name, t_fire, t_del in delivered:
        assert t_del - t_fire == pytest.approx(lat[name], abs=dt)
    # delivery order is by delivery time
    times = [t for _, _, t in delivered]
    assert times == sorted(times)


def test_bad_rate_rejected():
    with pytest.raises(ValueError, match="rate_hz"):
        SensorScheduler().add("x", 0.0)
