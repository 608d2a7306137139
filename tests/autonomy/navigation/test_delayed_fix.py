"""Late position fixes: fused at their measurement time by re-processing, they give the
estimate of the same fix fused on time; fused at the filter time, they do not."""

from __future__ import annotations

import numpy as np

from autonomy.messages import PositionFixMsg
from autonomy.navigation import NavigationFilter
from autonomy.navigation.config import NavigationConfig
from autonomy.navigation.delayed import DelayedFixFilter
from scenarios.schema import SensorsConfig
from sim.sensors.base import SceneView
from sim.sensors.nav_suite import build_nav_sensors
from tests.support import NAV_MOUNTS, NAV_NOISE, FLAT_SEABED_6M
from tests.support import survey_truths

SURVEY_DT_S = 0.1
SURVEY_TRUTHS = survey_truths(dt_s=SURVEY_DT_S, leg_s=40.0, n_legs=1)  # one straight leg, then a turn
LATENCY_S = 5.0
FIX_COV = np.diag([0.3**2, 0.3**2])


def _filter():
    tr = SURVEY_TRUTHS[0]
    return NavigationFilter(NavigationConfig(), tr.pos_ned, tr.rpy_rad[2], NAV_NOISE, mounts=NAV_MOUNTS)


def fly_filters(fix_every_s: float, seed: int = 3):
    """Feed three filters the same seeded messages: ``ontime`` gets each fix when it is
    measured, ``late`` (wrapped) gets it LATENCY_S later at its measurement time, ``naive``
    gets it LATENCY_S later applied at the filter time (the plain filter's behaviour)."""
    sensors = build_nav_sensors(SensorsConfig(), NAV_MOUNTS, seed)
    rng = np.random.default_rng(seed)
    ontime, naive = _filter(), _filter()
    late = DelayedFixFilter(_filter(), horizon_s=30.0, snapshot_every_s=1.0, gate_chi2=None)
    pending: list[PositionFixMsg] = []
    next_fix = fix_every_s
    t_last_fix = SURVEY_TRUTHS[-1].t_s - LATENCY_S - 1.0
    for tr in SURVEY_TRUTHS:
        msgs = [sensors["imu"].measure(tr), sensors["dvl"].measure(tr, SceneView(0.0, FLAT_SEABED_6M)),
                sensors["depth"].measure(tr)]
        handlers = late.message_handlers()
        for m in msgs:
            handlers[type(m)](m)
            for f in (ontime, naive):
                f.message_handlers()[type(m)](m)
        for f in (ontime, naive):
            f.predict(tr.t_s)
        late.predict(tr.t_s)
        if next_fix - 1e-9 <= tr.t_s <= t_last_fix:  # every fix reaches ``late`` before the end
            fix = PositionFixMsg(tr.t_s, tr.pos_ned[:2] + rng.multivariate_normal(np.zeros(2), FIX_COV), FIX_COV)
            ontime.on_position_fix(fix)
            pending.append(fix)
            next_fix += fix_every_s
        while pending and tr.t_s >= pending[0].t_s + LATENCY_S - 1e-9:
            fix = pending.pop(0)
            assert late.on_late_fix(fix)
            naive.on_position_fix(fix)
    return ontime, late, naive


def test_late_fix_equals_the_on_time_fix_and_the_naive_one_lags():
    ontime, late, naive = fly_filters(fix_every_s=8.0)
    # after the last fix has arrived, the re-processed estimate is the on-time one
    np.testing.assert_allclose(late.state, ontime.state, atol=1e-9)
    np.testing.assert_allclose(late.covariance, ontime.covariance, atol=1e-12)
    assert late.n_late_fused == int((SURVEY_TRUTHS[-1].t_s - LATENCY_S - 1.0) // 8.0) > 5
    # applied at the filter time, the same fixes pull the estimate back along the track
    truth = SURVEY_TRUTHS[-1].pos_ned[:2]
    err_naive = np.linalg.norm(naive.state[:2] - truth)
    err_late = np.linalg.norm(late.state[:2] - truth)
    assert err_late < 0.5
    assert err_naive > err_late + 0.5


def test_late_fix_beyond_the_history_is_refused():
    f = DelayedFixFilter(_filter(), horizon_s=2.0, snapshot_every_s=0.5)
    for k in range(1, 60):
        f.predict(k * SURVEY_DT_S)
    before = f.state
    assert not f.on_late_fix(PositionFixMsg(0.5, before[:2], FIX_COV))
    assert f.n_late_too_old == 1
    np.testing.assert_array_equal(f.state, before)
