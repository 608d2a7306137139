"""Time-division slots: packets released by each side arrive (travel time and guard
included) inside its slot, never in the other's, and the AUV's queue drains packet by packet."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.comms.tdma import AUV, SURFACE, SlotSender, TdmaSchedule


def test_slot_ends():
    s = TdmaSchedule(cycle_s=1.0, surface_slot_s=0.2, guard_s=0.05)
    assert s.slot_end_s(SURFACE, 3.05) == pytest.approx(3.2)
    assert s.slot_end_s(SURFACE, 3.5) == -math.inf
    assert s.slot_end_s(AUV, 3.5) == pytest.approx(4.0)
    assert s.slot_end_s(AUV, 3.1) == -math.inf
    assert s.fits(SURFACE, 3.0, 0.1, 0.0) and not s.fits(SURFACE, 3.1, 0.1, 0.0)
    # the travel time counts: 0.1 s packet + 0.05 s travel + 0.05 s guard fills the 0.2 s slot
    assert s.fits(SURFACE, 3.0, 0.1, 0.05) and not s.fits(SURFACE, 3.0, 0.1, 0.051)
    assert s.fits(AUV, 3.2, 0.5, 0.25) and not s.fits(AUV, 3.2, 0.5, 0.26)
    with pytest.raises(ValueError, match="travel_s"):
        s.fits(SURFACE, 3.0, 0.1, -0.01)
    # reach: c * (slot - duration - guard - multipath delay)
    assert s.reach_m(SURFACE, 0.1, 1500.0, 0.02) == pytest.approx(1500.0 * (0.2 - 0.1 - 0.05 - 0.02))
    assert s.reach_m(AUV, 0.1, 1500.0, 0.0) == pytest.approx(1500.0 * (0.8 - 0.1 - 0.05))
    with pytest.raises(ValueError):
        TdmaSchedule(cycle_s=1.0, surface_slot_s=1.0, guard_s=0.0)
    with pytest.raises(ValueError):
        s.slot_end_s("diver", 0.0)


@pytest.mark.parametrize("travel_s", [0.0, 0.06])
def test_released_packets_stay_in_their_slots(travel_s):
    s = TdmaSchedule(cycle_s=1.0, surface_slot_s=0.2, guard_s=0.05)
    duration = lambda n: (n + 16) * 8 / 8000.0  # noqa: E731 - 48 ms for 32 bytes
    auv, buoy = SlotSender(s, AUV, max_age_s=5.0), SlotSender(s, SURFACE)
    rng = np.random.default_rng(0)
    on_air = []  # (start, end, node)
    for k in range(300):  # 30 s of 10 Hz ticks
        t = round(k * 0.1, 10)
        for _ in range(rng.poisson(1.0)):  # ~10 detections/s
            auv.put(t, bytes(32))
        if k % 10 == 3:
            buoy.replace(t, bytes(37))
        for node, sender, n in ((AUV, auv, 32), (SURFACE, buoy, 37)):
            start = max([e for _, e, who in on_air if who == node] + [t])
            for _ in sender.release(t, duration, travel_s):
                on_air.append((start, start + duration(n), node))
                start += duration(n)
    for start, end, node in on_air:
        phase0 = start - math.floor(start) + 0.0
        phase1 = phase0 + (end - start) + travel_s + s.guard_s  # arrived, guard to spare
        if node == SURFACE:
            assert phase0 < 0.2 and phase1 <= 0.2 + 1e-9
        else:
            assert phase0 >= 0.2 - 1e-9 and phase1 <= 1.0 + 1e-9
    n_auv = sum(1 for *_, n in on_air if n == AUV)
    assert n_auv > 250  # most of the ~300 queued detections went out; the rest aged out or wait
    assert sum(1 for *_, n in on_air if n == SURFACE) >= 29  # a fix in (nearly) every cycle


def test_replace_counts_the_superseded():
    s = TdmaSchedule(cycle_s=1.0, surface_slot_s=0.2, guard_s=0.05)
    buoy = SlotSender(s, SURFACE)
    buoy.replace(0.5, b"a")  # the AUV's slot: waits
    buoy.replace(0.7, b"b")
    assert buoy.n_superseded == 1 and len(buoy) == 1
    assert buoy.release(1.0, lambda n: 0.05, 0.05) == [b"b"]
    buoy.replace(1.1, b"c")  # 0.05 + 0.1 travel + 0.05 guard from 1.1 ends past 1.2: waits
    assert buoy.release(1.1, lambda n: 0.05, 0.1) == [] and buoy.release(2.0, lambda n: 0.05, 0.1) == [b"c"]
    assert buoy.n_superseded == 1
