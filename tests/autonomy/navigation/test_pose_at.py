"""The navigation estimate moved to a measurement's time: against a vehicle on a circle (known
pose at every time), and in the scanning-sonar buffer, which places echoes with it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.messages import MsisPing, NavEstimate
from autonomy.msis.sonar_buffer import SonarBuffer
from autonomy.navigation.pose_at import estimate_at, pose_at

U, R_YAW, PSI0 = 0.85, 0.3, 0.4  # m/s, rad/s, rad: a constant turn


def circle(t: float) -> tuple[np.ndarray, float]:
    """Body origin (3,) NED m and yaw rad at ``t`` on the circle (north-east, depth 5 m)."""
    psi = PSI0 + R_YAW * t
    return np.array([U / R_YAW * (math.sin(psi) - math.sin(PSI0)), -U / R_YAW * (math.cos(psi) - math.cos(PSI0)),
                     5.0]), psi


def nav_on_circle(t: float) -> NavEstimate:
    pos, psi = circle(t)
    return NavEstimate(t, pos, np.array([0.0, 0.0, psi]), np.array([U, 0.0, 0.0]), np.array([0.0, 0.0, R_YAW]),
                       np.eye(3))


@pytest.mark.parametrize("gap_s", [0.02, 0.007, -0.015])
def test_pose_at_follows_the_turn_over_a_gap(gap_s):
    nav = nav_on_circle(2.0)
    pos, rpy = pose_at(nav, 2.0 + gap_s)
    want_pos, want_psi = circle(2.0 + gap_s)
    assert rpy[2] == pytest.approx(want_psi, abs=1e-12)  # constant rate: the heading is exact
    # first order: the chord of the arc, off by u r gap^2 / 2
    assert np.linalg.norm(pos - want_pos) <= 0.5 * U * R_YAW * gap_s**2 * 1.01
    moved = estimate_at(nav, 2.0 + gap_s)
    assert moved.t_s == 2.0 + gap_s and np.array_equal(moved.pos_ned, pos) and moved.cov_pos_ned is nav.cov_pos_ned
    assert estimate_at(nav, 2.0) is nav


def test_scanning_sonar_echo_is_placed_with_the_heading_of_the_ping_time():
    # a starboard beam (100 grad) with an echo 8 m out, the ping 15 ms after the filter's time:
    # held, the heading is 4.5 mrad old and the echo 3.6 cm off
    spacing = 0.02
    intensity = np.zeros(600, np.uint8)
    intensity[400] = 255
    t_ping = 1.0
    ping = MsisPing(t_s=t_ping, angle_grad=100.0, step_grad=1, sample_period_ticks=80, sample_spacing_m=spacing,
                    transmit_duration_us=50.0, speed_of_sound_mps=1500.0, intensity=intensity,
                    mount_pos_body_m=np.array([0.3, 0.0, 0.1]), mount_rpy_rad=np.zeros(3))
    buf = SonarBuffer(threshold_u8=200, min_range_m=0.5)
    assert buf.add_ping(ping, nav_on_circle(t_ping - 0.015)) == 1
    pos, psi = circle(t_ping)
    body = np.array([0.3, 400.5 * spacing, 0.0])  # the head's offset plus the range to starboard
    c, s = math.cos(psi), math.sin(psi)
    want = pos[:2] + np.array([c * body[0] - s * body[1], s * body[0] + c * body[1]])
    np.testing.assert_allclose(buf.points_ne()[0], want, rtol=0, atol=1e-3)
