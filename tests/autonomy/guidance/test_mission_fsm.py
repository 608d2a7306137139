"""Mission state machine: nominal sequence and every abort."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.guidance.config import LosConfig, MissionConfig
from autonomy.guidance.mission import MissionFsm, MissionState
from autonomy.guidance.survey import SurveyGuidance
from autonomy.messages import NavEstimate

PARAMS = MissionConfig(dive_tolerance_m=0.2, dive_settle_s=1.0, dive_timeout_s=30.0,
                       bottom_lock_timeout_s=5.0, nav_timeout_s=2.0, safe_depth_min_m=0.5,
                       safe_depth_max_m=8.0, min_altitude_m=0.5)


def nav(t, n=0.0, e=0.0, depth=0.3, yaw=0.0, altitude=3.7, u=0.0):
    return NavEstimate(t_s=t, pos_ned=np.array([n, e, depth]), rpy_rad=np.array([0.0, 0.0, yaw]),
                       vel_body_mps=np.array([u, 0.0, 0.0]), rate_body_radps=np.zeros(3),
                       cov_pos_ned=np.eye(3) * 0.01, altitude_m=altitude)


def with_params(**changes):
    return PARAMS.model_copy(update=changes)


def make_fsm(params=PARAMS, altitude_mode=True):
    vert = dict(altitude_m=2.0) if altitude_mode else dict(depth_m=2.0)
    g = SurveyGuidance([[10.0, 0.0], [10.0, 10.0]], 0.5, LosConfig(acceptance_radius_m=1.0), **vert)
    return MissionFsm(params, g)


def run_dive(fsm, t0=0.0):
    """Feed a vehicle that descends from 0.3 m to 2 m (altitude 2) and settles."""
    t = t0
    for depth in np.linspace(0.3, 2.0, 18):
        sp = fsm.update(t, nav(t, depth=depth, altitude=4.0 - depth), True)
        t += 0.5
    for _ in range(4):
        sp = fsm.update(t, nav(t, depth=2.0, altitude=2.0), True)
        t += 0.5
    return t, sp


def test_nominal_sequence_idle_dive_survey_surface_done():
    fsm = make_fsm(with_params(start_delay_s=1.0))
    assert fsm.update(0.0, nav(0.0), True) is None and fsm.state is MissionState.IDLE
    sp = fsm.update(1.0, nav(1.0, yaw=0.3), True)
    assert fsm.state is MissionState.DIVE
    assert sp.speed_mps == 0.0 and sp.altitude_m == 2.0 and sp.heading_rad == pytest.approx(0.3)
    t, sp = run_dive(fsm, 1.5)
    assert fsm.state is MissionState.SURVEY
    # fly the two waypoints
    for pos in ([5.0, 0.0], [9.8, 0.1], [10.0, 5.0], [10.0, 9.9]):
        sp = fsm.update(t, nav(t, *pos, depth=2.0, altitude=2.0, u=0.5), True)
        t += 0.5
    assert fsm.state is MissionState.SURFACE
    assert sp.depth_m == 0.0 and sp.speed_mps == 0.0
    fsm.update(t, nav(t, 10.0, 10.0, depth=1.0, altitude=3.0), True)
    assert fsm.state is MissionState.SURFACE
    fsm.update(t + 1, nav(t + 1, 10.0, 10.0, depth=0.2, altitude=3.8), True)
    assert fsm.done and fsm.succeeded and fsm.abort_reason is None
    states = [tr.to_state for tr in fsm.transitions]
    assert states == [MissionState.DIVE, MissionState.SURVEY, MissionState.SURFACE, MissionState.DONE]


def test_survey_setpoint_follows_los():
    fsm = make_fsm()
    fsm.update(0.0, nav(0.0), True)
    t, _ = run_dive(fsm, 0.5)
    sp = fsm.update(t, nav(t, 5.0, 1.0, depth=2.0, altitude=2.0, u=0.5), True)
    # the segment runs north from the dive point (0, 0): 1 m to starboard -> steer port
    assert sp.heading_rad == pytest.approx(-math.atan2(1.0, 3.0), abs=1e-9)
    assert sp.altitude_m == 2.0


def _surveying(altitude_mode=True):
    fsm = make_fsm(altitude_mode=altitude_mode)
    fsm.update(0.0, nav(0.0), True)
    t, _ = run_dive(fsm, 0.5)
    assert fsm.state is MissionState.SURVEY
    return fsm, t


@pytest.mark.parametrize(
    "bad_nav,match",
    [
        (dict(depth=9.0, altitude=1.0), "safe_depth_max_m"),
        (dict(depth=0.4, altitude=3.6), "safe_depth_min_m"),
        (dict(depth=2.0, altitude=0.3), "min_altitude_m"),
    ],
)
def test_aborts_on_depth_band_and_altitude(bad_nav, match):
    fsm, t = _surveying()
    sp = fsm.update(t, nav(t, 1.0, 0.0, **bad_nav), True)
    assert fsm.state is MissionState.ABORT and match in fsm.abort_reason
    assert sp.depth_m == 0.0 and sp.speed_mps == 0.0
    fsm.update(t + 10, nav(t + 10, 1.0, 0.0, depth=0.1, altitude=3.9), True)
    assert fsm.done and not fsm.succeeded


def test_abort_on_bottom_lock_lost_too_long_but_not_briefly():
    fsm, t = _surveying()
    for k in range(8):  # 4 s without lock < 5 s timeout
        fsm.update(t, nav(t, 0.1 * k, 0.0, depth=2.0, altitude=2.0), False)
        t += 0.5
    fsm.update(t, nav(t, 1.0, 0.0, depth=2.0, altitude=2.0), True)
    assert fsm.state is MissionState.SURVEY
    for k in range(12):
        fsm.update(t, nav(t, 1.0, 0.0, depth=2.0, altitude=2.0), False)
        t += 0.5
    assert fsm.state is MissionState.ABORT and "bottom lock" in fsm.abort_reason
    aborted_at = fsm.transitions[-1].t_s
    assert 5.0 < aborted_at - (t - 6.0) <= 5.5


def test_abort_on_missing_navigation():
    fsm, t = _surveying()
    fsm.update(t + 1.0, None, True)
    assert fsm.state is MissionState.SURVEY
    sp = fsm.update(t + 2.5, None, True)
    assert fsm.state is MissionState.ABORT and "navigation" in fsm.abort_reason
    assert sp.depth_m == 0.0


def test_abort_on_dive_timeout_and_mission_time():
    fsm = make_fsm()
    fsm.update(0.0, nav(0.0), True)
    for t in np.arange(0.5, 31.0, 0.5):  # stuck near the surface
        fsm.update(t, nav(t, depth=0.4, altitude=3.6), True)
    assert fsm.state is MissionState.ABORT and "dive_timeout_s" in fsm.abort_reason
    assert 30.0 < fsm.transitions[-1].t_s <= 30.5
    # an abort at the surface ends at once
    fsm.update(31.0, nav(31.0, depth=0.2, altitude=3.8), True)
    assert fsm.done and not fsm.succeeded
    fsm = make_fsm(with_params(max_mission_time_s=5.0))
    fsm.update(0.0, nav(0.0), True)
    fsm.update(6.0, nav(6.0, depth=1.0, altitude=3.0), True)
    assert fsm.state is MissionState.ABORT and "max_mission_time_s" in fsm.abort_reason


def test_external_abort_and_depth_mode_dive():
    fsm = make_fsm(altitude_mode=False)
    fsm.update(0.0, nav(0.0), True)
    t, sp = run_dive(fsm, 0.5)
    assert fsm.state is MissionState.SURVEY and sp.depth_m == 2.0
    fsm.abort(t, "operator")
    assert fsm.state is MissionState.ABORT and fsm.abort_reason == "operator"


def test_band_validation():
    with pytest.raises(ValueError, match="safe_depth_min_m"):
        MissionConfig(safe_depth_min_m=5.0, safe_depth_max_m=4.0)


def test_mode_names_and_reset():
    fsm, t = _surveying()
    assert fsm.mode == "survey" and not fsm.aborted
    fsm.abort(t, "operator")
    assert fsm.mode == "abort" and fsm.aborted
    fsm.reset()
    assert fsm.mode == "idle" and not fsm.aborted and fsm.transitions == []
    fsm2 = MissionFsm(MissionConfig(dive_settle_s=0.0), fsm.guidance)
    fsm2.update(0.0, nav(0.0, depth=2.0, altitude=2.0), True)
    assert fsm2.update(0.1, nav(0.1, depth=2.0, altitude=2.0), True) is not None
    assert fsm2.mode == "survey"
