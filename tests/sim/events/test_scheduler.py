"""Multi-rate scheduling: sensors fire at their rates and messages arrive after their latency."""

from __future__ import annotations

import numpy as np
import pytest

from sim.events.scheduler import SensorScheduler


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


def test_a_sensor_faster_than_the_step_fires_at_every_own_time_without_drift():
    # 400 Hz and 3 Hz on a 200 Hz clock for 100 s: the n-th firing at exactly n / rate (the
    # 400 Hz one twice per step, the 3 Hz one between steps), none skipped
    dt = 1.0 / 200.0
    sch = SensorScheduler(eps_s=1e-6 * dt)
    sch.add("imu", 400.0)
    sch.add("fls", 3.0)
    sch.reset(0.0)
    fired = {"imu": [], "fls": []}
    times = []
    for k in range(0, 20001):
        for t_fire, name in sch.take_due(k * dt):
            fired[name].append(t_fire)
            times.append(t_fire)
            assert (k - 1) * dt < t_fire <= k * dt + 1e-12  # within the step just taken
    assert len(fired["imu"]) == 40001 and len(fired["fls"]) == 301
    np.testing.assert_allclose(fired["imu"], np.arange(40001) / 400.0, rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(fired["fls"], np.arange(301) / 3.0, rtol=0.0, atol=1e-12)
    assert times == sorted(times)  # in time order across the channels


def test_first_firing_at_the_reset_time_and_ties_in_table_order():
    sch = SensorScheduler()
    sch.add("a", 50.0)
    sch.add("b", 100.0)
    sch.reset(0.0)
    assert sch.take_due(0.0) == [(0.0, "a"), (0.0, "b")]
    assert sch.next_fire_s == pytest.approx(0.01)
    assert sch.take_due(0.02) == [(0.01, "b"), (0.02, "a"), (0.02, "b")]


def test_phases_are_taken_apart_and_an_offset_delays_the_first_firing():
    from sim.events.scheduler import AUTONOMY

    sch = SensorScheduler()
    sch.add("imu", 10.0)
    sch.add("link", 2.0, quantum_s=0.1, phase=AUTONOMY, offset_s=0.5)
    sch.reset(0.0)
    assert sch.next_fire_s == 0.0  # the physics phase's next firing only
    physics, autonomy = [], []
    for k in range(0, 21):  # 0 .. 2 s in 0.1 s ticks
        t = round(k * 0.1, 10)
        physics += sch.due(t)
        autonomy += [(round(t_f, 9), name) for t_f, name in sch.take_due(t, AUTONOMY)]
    assert physics == ["imu"] * 21  # the autonomy channel is never taken with the physics one
    assert autonomy == [(0.5, "link"), (1.0, "link"), (1.5, "link"), (2.0, "link")]  # from one period on
    added = SensorScheduler()  # added after a reset: the offset applies from the first firing too
    added.add("link", 2.0, first_fire_s=1.0, quantum_s=0.1, phase=AUTONOMY, offset_s=0.5)
    assert added.take_due(1.4, AUTONOMY) == [] and added.take_due(1.5, AUTONOMY) == [(1.5, "link")]
    sch.reset(3.0)
    assert sch.take_due(3.0, AUTONOMY) == [] and sch.take_due(3.5, AUTONOMY) == [(3.5, "link")]


def test_bad_phase_and_offset_rejected():
    sch = SensorScheduler()
    with pytest.raises(ValueError, match="phase must be one of"):
        sch.add("x", 1.0, phase="later")
    with pytest.raises(ValueError, match="offset_s must be >= 0"):
        sch.add("x", 1.0, offset_s=-1.0)
