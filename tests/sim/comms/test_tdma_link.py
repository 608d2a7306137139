"""Time-division slots on the simulated half-duplex link: with the travel time in the slot
plan, nothing is lost to half duplex at any range, and a slot carries its packet exactly
to its reach (c * (slot - duration - guard - multipath delay)), beyond which it waits."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.comms.tdma import AUV, SURFACE, SlotSender, TdmaSchedule
from scenarios.config.comms import AcousticLinkConfig
from sim.comms import AcousticLink

C = 1500.0
GUARD_S = 0.05
DET_BYTES, FIX_BYTES = 33, 38  # the version-2 messages
#: slot plans: (bit rate, cycle, surface slot): the config defaults, the sea trial's, and a
#: default plan whose surface slot is long enough for a fix at 600 m
PLANS = {"default": (1000.0, 2.0, 0.6), "sea_trial": (8000.0, 1.0, 0.3), "long_surface_slot": (1000.0, 2.0, 1.0)}


def _run(range_m, rate_bps, cycle_s, slot_s, n_cycles=60, dt=0.1, seed=0):
    """An AUV ``range_m`` from the buoy with ~10 detections/s queued (more than its slot
    carries) and a fix made every cycle at a random tick, driven as the mission drives them:
    each tick, release what fits, send it, advance the link. Channel losses off, multipath
    on (half the packets, up to 50 ms late)."""
    cfg = AcousticLinkConfig(bit_rate_bps=rate_bps, overhead_bytes=16, sound_speed_mps=C, loss_near=0.0,
                             loss_far=0.0, noise_loss_per_mps=0.0, multipath_prob=0.5, multipath_max_delay_s=0.05)
    link = AcousticLink(cfg, ["auv", "buoy"], np.random.default_rng(seed))
    rng = np.random.default_rng(seed + 1)
    schedule = TdmaSchedule(cycle_s, slot_s, GUARD_S)
    up, down = SlotSender(schedule, AUV, max_age_s=30.0), SlotSender(schedule, SURFACE)
    pos = {"auv": np.array([range_m, 0.0, 0.0]), "buoy": np.zeros(3)}
    travel_s = range_m / C + cfg.multipath_max_delay_s
    ticks = int(round(cycle_s / dt))
    fix_tick = 0
    for k in range(n_cycles * ticks):
        t = round(k * dt, 9)
        if k % ticks == 0:
            fix_tick = int(rng.integers(0, ticks))
        for _ in range(rng.poisson(1.0)):
            up.put(t, bytes(DET_BYTES))
        if k % ticks == fix_tick:
            down.replace(t, bytes(FIX_BYTES))
        for payload in up.release(t, cfg.packet_duration_s, travel_s):
            link.send(t, "auv", "buoy", payload)
        for payload in down.release(t, cfg.packet_duration_s, travel_s):
            link.send(t, "buoy", "auv", payload)
        link.advance(t, pos)
    link.advance(t + 10.0, pos)
    return cfg, link, down


@pytest.mark.parametrize("plan", list(PLANS))
@pytest.mark.parametrize("range_m", [300.0, 600.0])
def test_no_half_duplex_loss_and_each_slot_carries_its_packet_to_its_reach(range_m, plan):
    rate_bps, cycle_s, slot_s = PLANS[plan]
    cfg, link, down = _run(range_m, rate_bps, cycle_s, slot_s)
    up_st, down_st = link.stats("auv", "buoy"), link.stats("buoy", "auv")
    # written out: the packet, its flight (range / c + the longest multipath delay) and the guard in the slot
    flight_s = range_m / C + 0.05 + GUARD_S
    fix_fits = (FIX_BYTES + 16) * 8 / rate_bps + flight_s <= slot_s
    det_fits = (DET_BYTES + 16) * 8 / rate_bps + flight_s <= cycle_s - slot_s
    assert det_fits  # every plan's AUV slot carries detections to 600 m
    for st in (up_st, down_st):
        assert (st.lost_half_duplex, st.lost_collision, st.lost_channel, st.pending) == (0, 0, 0, 0)
    assert up_st.delivered == up_st.sent > 0
    if fix_fits:  # a fix in (nearly) every cycle: one made late in a cycle may be replaced before it fits
        assert down_st.delivered == down_st.sent >= 50
        assert down_st.sent + down.n_superseded + len(down) == 60
    else:  # beyond the surface slot's reach the fix waits, never sent into the AUV's slot
        assert down_st.sent == 0 and down.n_superseded + len(down) == 60


def test_the_cases_cover_both_sides_of_the_reach():
    """The default and sea-trial surface slots carry a fix to 102 m and 219 m, the long one
    to 702 m: the test above checks both branches at both ranges."""
    reach = {name: TdmaSchedule(cycle, slot, GUARD_S).reach_m(SURFACE, (FIX_BYTES + 16) * 8 / rate, C, 0.05)
             for name, (rate, cycle, slot) in PLANS.items()}
    assert reach == pytest.approx({"default": 1500 * (0.6 - 0.432 - 0.1), "sea_trial": 1500 * (0.3 - 0.054 - 0.1),
                                   "long_surface_slot": 1500 * (1.0 - 0.432 - 0.1)})
    assert max(reach["default"], reach["sea_trial"]) < 300.0 and reach["long_surface_slot"] >= 600.0
