"""SurveyGuidance: LOS heading, sideslip compensation, slow-down in turns, end of survey."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.guidance.config import GuidanceConfig, LosConfig, SurveyConfig
from autonomy.guidance.survey import SurveyGuidance
from autonomy.messages import NavEstimate


def nav(t, n, e, yaw, u=0.5, v=0.0):
    return NavEstimate(t_s=t, pos_ned=np.array([n, e, 2.0]), rpy_rad=np.array([0.0, 0.0, yaw]),
                       vel_body_mps=np.array([u, v, 0.0]), rate_body_radps=np.zeros(3),
                       cov_pos_ned=np.eye(3), altitude_m=2.0)


def test_heading_speed_and_sideslip_compensation():
    los = LosConfig(lookahead_m=2.0, sideslip_filter_tau_s=1.0, slow_down_heading_error_deg=90.0,
                    min_speed_fraction=0.25)
    g = SurveyGuidance([[0.0, 100.0]], 0.8, los, altitude_m=2.0)  # eastbound line
    g.start([0.0, 0.0])
    sp = g.update(nav(0.0, 0.0, 1.0, math.pi / 2))
    assert sp.heading_rad == pytest.approx(math.pi / 2) and sp.speed_mps == pytest.approx(0.8)
    assert sp.altitude_m == 2.0 and sp.depth_m is None
    # 45 deg heading error -> speed falls linearly to half of the way to the floor at 90 deg
    sp = g.update(nav(0.1, 0.0, 1.0, math.pi / 4))
    assert sp.speed_mps == pytest.approx(0.8 * 0.5)
    sp = g.update(nav(0.2, 0.0, 1.0, -math.pi / 2))
    assert sp.speed_mps == pytest.approx(0.8 * 0.25)
    # steady drift to port (v < 0): sideslip converges to atan2(v, u); heading = course - beta
    for k in range(100):
        sp = g.update(nav(0.3 + 0.1 * k, 0.0, 2.0 + 0.05 * k, math.pi / 2, u=0.5, v=-0.1))
    beta = math.atan2(-0.1, 0.5)
    assert g.sideslip_rad == pytest.approx(beta, rel=1e-3)
    assert sp.heading_rad == pytest.approx(math.pi / 2 - beta, rel=1e-3)  # crab to starboard


def test_holds_heading_with_zero_speed_after_the_last_waypoint():
    g = SurveyGuidance([[0.0, 5.0]], 0.5, LosConfig(acceptance_radius_m=1.0), depth_m=3.0)
    g.start([0.0, 0.0])
    g.update(nav(0.0, 0.0, 2.0, 1.5))
    sp = g.update(nav(1.0, 0.0, 4.5, 1.5))
    assert g.finished and sp.speed_mps == 0.0 and sp.depth_m == 3.0
    assert sp.heading_rad == pytest.approx(math.pi / 2)


def test_from_config_depth_mode_and_bad_arguments():
    cfg = GuidanceConfig(survey=SurveyConfig(vertical_mode="depth", depth_m=1.5, width_m=0.0))
    g = SurveyGuidance.from_config(cfg.survey, cfg.los)
    assert g.depth_m == 1.5 and g.altitude_m is None
    assert g.plan is not None and g.plan.n_legs == 1
    with pytest.raises(ValueError, match="exactly one"):
        SurveyGuidance([[1.0, 1.0]], 0.5)
    with pytest.raises(ValueError, match="speed_mps"):
        SurveyGuidance([[1.0, 1.0]], 0.0, depth_m=1.0)
    with pytest.raises(ValueError):
        SurveyConfig(leg_spacing_m="auto")


def test_fixed_heading_moves_along_the_path_by_surge_and_sway():
    """An omnidirectional vehicle holding north on an eastbound line moves by sway alone
    (starboard > 0); yawed 30 deg off, the body velocity setpoint still points east in NED."""
    g = SurveyGuidance([[0.0, 100.0]], 0.3, LosConfig(lookahead_m=2.0), depth_m=5.0, heading_rad=0.0)
    g.start([0.0, 0.0])
    sp = g.update(nav(0.0, 0.0, 1.0, 0.0))
    assert sp.heading_rad == 0.0 and sp.speed_mps == pytest.approx(0.0, abs=1e-12)
    assert sp.sway_mps == pytest.approx(0.3)
    yaw = math.radians(30.0)
    sp = g.update(nav(0.1, 0.0, 1.0, yaw))
    v_ned = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]]) @ [sp.speed_mps, sp.sway_mps]
    np.testing.assert_allclose(v_ned, [0.0, 0.3], atol=1e-12)
    assert sp.heading_rad == 0.0
