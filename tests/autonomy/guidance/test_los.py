"""LOS geometry and convergence, and the waypoint manager's switching."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from autonomy.guidance.los import los_course_rad, path_errors
from autonomy.guidance.waypoints import WaypointManager


def test_path_errors_geometry():
    # Segment heading north-east; a point 1 m to its starboard side and 2 m along.
    p0, p1 = np.array([1.0, 1.0]), np.array([4.0, 4.0])
    d = (p1 - p0) / np.linalg.norm(p1 - p0)
    starboard = np.array([-d[1], d[0]])
    pos = p0 + 2.0 * d + 1.0 * starboard
    e = path_errors(p0, p1, pos)
    assert e.path_angle_rad == pytest.approx(math.pi / 4)
    assert e.along_track_m == pytest.approx(2.0)
    assert e.cross_track_m == pytest.approx(1.0)
    assert e.length_m == pytest.approx(3.0 * math.sqrt(2.0))
    # heading east, starboard is south
    assert path_errors([0, 0], [0, 10], [-2.0, 3.0]).cross_track_m == pytest.approx(2.0)
    with pytest.raises(ValueError):
        path_errors([0, 0], [0, 0], [1, 1])


def test_los_course_points_at_lookahead_point():
    e = path_errors([0, 0], [10, 0], [0.0, 3.0])  # 3 m east (starboard) of a northbound line
    chi = los_course_rad(e, lookahead_m=3.0)
    assert chi == pytest.approx(-math.pi / 4)  # 45 deg back towards the line
    on_line = path_errors([0, 0], [0, 10], [0.0, 5.0])
    assert los_course_rad(on_line, 2.0) == pytest.approx(math.pi / 2)
    # wrapping: path heading south (pi), vehicle to starboard (west) -> course just past pi
    south = path_errors([0, 0], [-10, 0], [-1.0, -0.5])
    assert -math.pi <= los_course_rad(south, 3.0) < math.pi


def test_los_cross_track_convergence_matches_analytic_ode():
    """Kinematic vehicle steering the LOS course: e(t) obeys de/dt = -U e / sqrt(e^2 + D^2).

    The vehicle is integrated in NE coordinates (Euler, small step); the oracle integrates
    the scalar ODE with solve_ivp.
    """
    U, D, e0, T, dt = 0.5, 3.0, 6.0, 60.0, 0.005
    p0, p1 = np.array([0.0, 0.0]), np.array([1000.0, 0.0])
    pos = np.array([0.0, e0])
    n = int(T / dt)
    es = np.empty(n + 1)
    es[0] = e0
    for k in range(n):
        chi = los_course_rad(path_errors(p0, p1, pos), D)
        pos = pos + dt * U * np.array([math.cos(chi), math.sin(chi)])
        es[k + 1] = path_errors(p0, p1, pos).cross_track_m
    sol = solve_ivp(lambda t, e: -U * e / np.sqrt(e * e + D * D), (0, T), [e0],
                    t_eval=np.linspace(0, T, 7), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(es[:: n // 6], sol.y[0], atol=5e-3)
    assert np.all(np.diff(es) <= 0.0)  # monotone approach, no overshoot
    assert abs(es[-1]) < 0.02


def test_waypoint_manager_switches_in_circle_or_past_perpendicular():
    wm = WaypointManager([[10.0, 0.0], [10.0, 10.0]], acceptance_radius_m=1.0)
    wm.start([0.0, 0.0])
    err = wm.update([5.0, 0.0], 1.0)
    assert wm.index == 0 and err.along_track_m == pytest.approx(5.0)
    wm.update([9.5, 0.2], 2.0)  # inside the acceptance circle
    assert wm.index == 1 and wm.reached_t_s[0] == 2.0
    # wide of the circle but past the perpendicular through waypoint 1
    assert wm.update([13.0, 10.5], 3.0) is None
    assert wm.finished
    np.testing.assert_allclose(wm.reached_pos_ne_m[1], [13.0, 10.5])
    with pytest.raises(ValueError):
        WaypointManager([[0.0, 0.0, 0.0]], 1.0)
    with pytest.raises(ValueError):
        WaypointManager([[0.0, 0.0]], 0.0)
