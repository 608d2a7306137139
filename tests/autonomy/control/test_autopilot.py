"""Autopilot sign conventions, reference shaping and altitude mode (open loop, one step)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.control.autopilot import Autopilot
from autonomy.control.config import ControlConfig, PidConfig
from autonomy.control.setpoint import Setpoint
from autonomy.messages import NavEstimate

P_ONLY = ControlConfig(surge=PidConfig(kp=10.0), sway=PidConfig(kp=10.0), heading=PidConfig(kp=10.0),
                       depth=PidConfig(kp=10.0), max_yaw_rate_dps=10.0,
                       max_vertical_speed_mps=0.2, max_acceleration_mps2=0.1, altitude_filter_tau_s=0.0)


def nav(depth=1.0, yaw=0.0, u=0.0, v=0.0, altitude=float("nan"), t=0.0):
    return NavEstimate(t_s=t, pos_ned=np.array([0.0, 0.0, depth]), rpy_rad=np.array([0.0, 0.0, yaw]),
                       vel_body_mps=np.array([u, v, 0.0]), rate_body_radps=np.zeros(3),
                       cov_pos_ned=np.eye(3), altitude_m=altitude)


def test_signs_and_no_roll_pitch_moment():
    ap = Autopilot(P_ONLY)
    ap.update(nav(), Setpoint(0.0, 0.0, depth_m=1.0), 0.1)  # engage at the current state
    w = ap.update(nav(), Setpoint(1.0, math.radians(30.0), depth_m=3.0, sway_mps=0.5), 1.0)
    assert w.shape == (6,)
    assert w[3] == 0.0 and w[4] == 0.0
    # references slew: speed +0.1, heading +10 deg, depth +0.2 in 1 s
    assert w[0] == pytest.approx(10.0 * 0.1)
    assert w[1] == pytest.approx(10.0 * 0.5)
    assert w[2] == pytest.approx(10.0 * 0.2)  # deeper -> push down (+Z, FRD)
    assert w[5] == pytest.approx(10.0 * math.radians(10.0))  # to starboard -> +N
    assert ap.heading_ref_rad == pytest.approx(math.radians(10.0))


def test_heading_takes_the_short_way_round():
    ap = Autopilot(P_ONLY)
    yaw = math.radians(-179.0)
    ap.update(nav(yaw=yaw), Setpoint(0.0, yaw, depth_m=1.0), 0.1)
    w = ap.update(nav(yaw=yaw), Setpoint(0.0, math.radians(179.0), depth_m=1.0), 0.1)
    assert w[5] < 0.0  # 2 deg to port across +-180
    assert abs(ap.heading_ref_rad - math.radians(-180.0)) < math.radians(1.01)


def test_altitude_mode_tracks_seabed_minus_altitude_and_holds_when_invalid():
    ap = Autopilot(P_ONLY)
    ap.update(nav(depth=1.0, altitude=3.0), Setpoint(0.0, 0.0, altitude_m=2.0), 0.1)
    assert ap.seabed_depth_m == pytest.approx(4.0)
    assert ap.depth_target_m == pytest.approx(2.0)
    # altitude lost: target stays at the last seabed estimate
    ap.update(nav(depth=1.5, altitude=float("nan")), Setpoint(0.0, 0.0, altitude_m=2.0), 0.1)
    assert ap.depth_target_m == pytest.approx(2.0)
    # never above the surface
    ap.update(nav(depth=1.0, altitude=0.5), Setpoint(0.0, 0.0, altitude_m=3.0), 0.1)
    assert ap.depth_target_m == 0.0
    # no altitude ever seen: hold the engage depth
    ap = Autopilot(P_ONLY)
    ap.update(nav(depth=1.2), Setpoint(0.0, 0.0, altitude_m=2.0), 0.1)
    assert ap.depth_target_m == pytest.approx(1.2)


def test_setpoint_validation():
    with pytest.raises(ValueError, match="exactly one"):
        Setpoint(0.5, 0.0)
    with pytest.raises(ValueError, match="exactly one"):
        Setpoint(0.5, 0.0, depth_m=1.0, altitude_m=2.0)
    with pytest.raises(ValueError, match="altitude_m"):
        Setpoint(0.5, 0.0, altitude_m=-1.0)
    with pytest.raises(ValueError, match="heading_rad"):
        Setpoint(0.5, float("nan"), depth_m=1.0)


def test_bad_control_config_rejected():
    with pytest.raises(ValueError):
        ControlConfig(surge={"kp": -1.0})
    with pytest.raises(ValueError):
        ControlConfig(surge={"kq": 1.0})


def test_derivative_uses_depth_and_yaw_rates_at_any_attitude():
    """D terms act on the NED depth rate and the Euler yaw rate (checked against frames)."""
    from autonomy.frames import euler_rate_matrix, rot_from_euler

    d_only = ControlConfig(surge=PidConfig(), sway=PidConfig(), heading=PidConfig(kd=2.0),
                           depth=PidConfig(kd=3.0))
    rpy = np.array([0.2, -0.15, 1.0])
    vel = np.array([0.4, -0.1, 0.05])
    rates = np.array([0.03, -0.02, 0.1])
    msg = NavEstimate(t_s=0.0, pos_ned=np.array([0.0, 0.0, 2.0]), rpy_rad=rpy, vel_body_mps=vel,
                      rate_body_radps=rates, cov_pos_ned=np.eye(3))
    ap = Autopilot(d_only)
    w = ap.update(msg, Setpoint(0.0, float(rpy[2]), depth_m=2.0), 0.1)  # references at the state
    assert w[2] == pytest.approx(-3.0 * (rot_from_euler(*rpy) @ vel)[2])
    assert w[5] == pytest.approx(-2.0 * (euler_rate_matrix(rpy[0], rpy[1]) @ rates)[2])


def test_non_finite_navigation_is_rejected_without_corrupting_state():
    ap = Autopilot(P_ONLY)
    ap.update(nav(), Setpoint(0.5, 0.0, depth_m=1.0), 0.1)
    with pytest.raises(ValueError, match="finite"):
        ap.update(nav(u=float("nan")), Setpoint(0.5, 0.0, depth_m=1.0), 0.1)
    assert np.all(np.isfinite(ap.update(nav(), Setpoint(0.5, 0.0, depth_m=1.0), 0.1)))
