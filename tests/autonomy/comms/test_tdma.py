"""Time-division slots: packets released by each side end (guard included) inside its slot,
never in the other's, and the AUV's queue drains packet by packet."""

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
    assert s.fits(SURFACE, 3.0, 0.1) and not s.fits(SURFACE, 3.1, 0.1)
    with pytest.raises(ValueError):
        TdmaSchedule(cycle_s=1.0, surface_slot_s=1.0, guard_s=0.0)
    with pytest.raises(ValueError):
        s.slot_end_s("diver", 0.0)


def test_released_packets_stay_in_their_slots():
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
            for _ in sender.release(t, duration):
                on_air.append((start, start + duration(n), node))
                start += duration(n)
    for start, end, node in on_air:
        phase0 = start - math.floor(start) + 0.0
        phase1 = phase0 + (end - start) + s.guard_s
        if node == SURFACE:
            assert phase0 < 0.2 and phase1 <= 0.2 + 1e-9
        else:
            assert phase0 >= 0.2 - 1e-9 and phase1 <= 1.0 + 1e-9
    n_auv = sum(1 for *_, n in on_air if n == AUV)
    assert n_auv > 250  # most of the ~300 queued detections went out; the rest aged out or wait
