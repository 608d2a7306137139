"""Kinematic trajectories and an analytic plane caster for the navigation tests (and checks of
them against independent finite differences / geometry)."""

from __future__ import annotations

import numpy as np

from autonomy.frames import euler_rate_matrix, rot_from_euler
from sim.sensors.raycast import RayHits
from sim.dynamics.truth import VehicleTruth

# ----------------------------------------------------------------------------- casters


class PlaneCaster:
    """Rays against one infinite plane through ``point_ned`` with unit ``normal_ned`` facing
    the vehicle (a flat seabed at depth D is point [0, 0, D], normal [0, 0, -1])."""

    def __init__(self, point_ned, normal_ned, reflectivity: float = 0.3):
        self.point = np.asarray(point_ned, float)
        n = np.asarray(normal_ned, float)
        self.normal = n / np.linalg.norm(n)
        self.reflectivity = reflectivity

    def cast(self, origin_ned, dirs_ned, max_range_m):
        dirs = np.atleast_2d(np.asarray(dirs_ned, float))
        denom = dirs @ self.normal
        with np.errstate(divide="ignore", invalid="ignore"):
            dist = ((self.point - origin_ned) @ self.normal) / denom
        hit = (denom < 0.0) & (dist > 0.0) & (dist <= max_range_m)
        return RayHits(
            dist_m=np.where(hit, dist, np.inf),
            normal_ned=np.where(hit[:, None], self.normal, 0.0),
            reflectivity=np.where(hit, self.reflectivity, 0.0),
            object_id=np.where(hit, -1, -2).astype(np.int64),
        )


def flat_seabed(depth_m: float) -> PlaneCaster:
    return PlaneCaster([0.0, 0.0, depth_m], [0.0, 0.0, -1.0])


# ----------------------------------------------------------------------------- trajectories


def _wiggle_pos(t):
    """Closed-form NED position (3,) and its first and second derivatives."""
    w1, w2, w3 = 0.21, 0.13, 0.07
    pos = np.array([0.4 * t + 2.0 * np.sin(w1 * t), 3.0 * (1.0 - np.cos(w2 * t)), 2.0 + 0.5 * np.sin(w3 * t)])
    vel = np.array([0.4 + 2.0 * w1 * np.cos(w1 * t), 3.0 * w2 * np.sin(w2 * t), 0.5 * w3 * np.cos(w3 * t)])
    acc = np.array([-2.0 * w1**2 * np.sin(w1 * t), 3.0 * w2**2 * np.cos(w2 * t), -0.5 * w3**2 * np.sin(w3 * t)])
    return pos, vel, acc


def _wiggle_rpy(t):
    rpy = np.array([0.08 * np.sin(0.5 * t), 0.06 * np.sin(0.3 * t + 0.4), 0.3 + 0.05 * t])
    rpy_dot = np.array([0.04 * np.cos(0.5 * t), 0.018 * np.cos(0.3 * t + 0.4), 0.05])
    return rpy, rpy_dot


def _omega(t):
    rpy, rpy_dot = _wiggle_rpy(t)
    return np.linalg.solve(euler_rate_matrix(rpy[0], rpy[1]), rpy_dot)


def wiggle_truth(t: float) -> VehicleTruth:
    """Closed-form 6-DOF trajectory (vehicle sways, rolls, pitches and turns) at time ``t``."""
    pos, vel_ned, acc_ned = _wiggle_pos(t)
    rpy, _ = _wiggle_rpy(t)
    R = rot_from_euler(*rpy)
    omega = _omega(t)
    v_body = R.T @ vel_ned
    v_dot = R.T @ acc_ned - np.cross(omega, v_body)  # d/dt (R^T v_n), R_dot = R S(omega)
    h = 1e-5
    omega_dot = (_omega(t + h) - _omega(t - h)) / (2 * h)
    return VehicleTruth(
        t_s=float(t), pos_ned=pos, R_nb=R, rpy_rad=rpy, nu=np.concatenate([v_body, omega]),
        nu_dot=np.concatenate([v_dot, omega_dot]), current_ned=np.zeros(3),
    )


def static_truth(pos_ned=(0.0, 0.0, 1.0), rpy_rad=(0.0, 0.0, 0.0), t_s: float = 0.0) -> VehicleTruth:
    rpy = np.asarray(rpy_rad, float)
    return VehicleTruth(t_s=t_s, pos_ned=np.asarray(pos_ned, float), R_nb=rot_from_euler(*rpy), rpy_rad=rpy,
                        nu=np.zeros(6), nu_dot=np.zeros(6), current_ned=np.zeros(3))


def survey_truths(dt_s: float = 0.1, speed_mps: float = 0.5, leg_s: float = 120.0, n_legs: int = 4,
                  surface_s: float = 30.0, depth_m: float = 2.0, yaw0_rad: float = 0.3) -> list[VehicleTruth]:
    """Lawnmower-like run sampled every ``dt_s``: a straight run at the surface, a dive,
    ``n_legs`` legs joined by 180 deg turns (0.1 rad/s), then a climb back to the surface.
    Body velocity [u, 0, w], small roll/pitch oscillation; position integrated with the
    trapezoid rule on a 10x finer grid."""
    turn_rate = 0.1
    turn_s = np.pi / turn_rate
    dive_s = 40.0
    schedule = surface_s + dive_s + n_legs * leg_s + (n_legs - 1) * turn_s + dive_s + surface_s
    sub = 10
    t = np.arange(0.0, schedule + 1e-9, dt_s / sub)

    # yaw rate profile: alternate left/right turns between legs
    yaw_rate = np.zeros_like(t)
    start = surface_s + dive_s + leg_s
    for k in range(n_legs - 1):
        in_turn = (t >= start) & (t < start + turn_s)
        yaw_rate[in_turn] = turn_rate * (1 if k % 2 == 0 else -1)
        start += turn_s + leg_s
    yaw = yaw0_rad + np.concatenate([[0.0], np.cumsum(0.5 * (yaw_rate[1:] + yaw_rate[:-1]) * np.diff(t))])

    # vertical: smooth dive and climb (w in NED), 0 elsewhere
    def bump(tt, t0, dur, dz):
        s = np.clip((tt - t0) / dur, 0.0, 1.0)
        inside = (tt > t0) & (tt < t0 + dur)
        return np.where(inside, dz / dur * (1.0 - np.cos(2 * np.pi * s)), 0.0)

    d_dot = bump(t, surface_s, dive_s, depth_m) + bump(t, schedule - surface_s - dive_s, dive_s, -depth_m)
    roll = np.radians(0.5) * np.sin(0.4 * t)
    pitch = np.radians(0.5) * np.sin(0.25 * t + 1.0)
    roll_dot = np.radians(0.5) * 0.4 * np.cos(0.4 * t)
    pitch_dot = np.radians(0.5) * 0.25 * np.cos(0.25 * t + 1.0)

    vel_ned = np.stack([speed_mps * np.cos(yaw), speed_mps * np.sin(yaw), d_dot], axis=1)
    pos = np.concatenate([[[0.0, 0.0, 0.0]], np.cumsum(0.5 * (vel_ned[1:] + vel_ned[:-1]) * np.diff(t)[:, None], axis=0)])
    acc_ned = np.gradient(vel_ned, t, axis=0)

    truths = []
    for i in range(0, len(t), sub):
        rpy = np.array([roll[i], pitch[i], yaw[i]])
        R = rot_from_euler(*rpy)
        omega = np.linalg.solve(euler_rate_matrix(roll[i], pitch[i]), [roll_dot[i], pitch_dot[i], yaw_rate[i]])
        v_body = R.T @ vel_ned[i]
        v_dot = R.T @ acc_ned[i] - np.cross(omega, v_body)
        truths.append(VehicleTruth(t_s=float(t[i]), pos_ned=pos[i].copy(), R_nb=R, rpy_rad=rpy,
                                   nu=np.concatenate([v_body, omega]), nu_dot=np.concatenate([v_dot, np.zeros(3)]),
                                   current_ned=np.zeros(3)))
    return truths


# ----------------------------------------------------------------------------- checks of the helpers


def test_wiggle_truth_velocities_match_finite_differences():
    h = 1e-4
    for t in (0.0, 7.3, 41.0):
        tr = wiggle_truth(t)
        fd_vel_ned = (wiggle_truth(t + h).pos_ned - wiggle_truth(t - h).pos_ned) / (2 * h)
        np.testing.assert_allclose(tr.vel_ned_mps, fd_vel_ned, atol=1e-7)
        fd_nu = (wiggle_truth(t + h).nu - wiggle_truth(t - h).nu) / (2 * h)
        np.testing.assert_allclose(tr.nu_dot, fd_nu, atol=1e-6)
        # angular velocity from the rotation matrix: R^T R_dot = S(omega)
        R_dot = (wiggle_truth(t + h).R_nb - wiggle_truth(t - h).R_nb) / (2 * h)
        S = tr.R_nb.T @ R_dot
        np.testing.assert_allclose([S[2, 1], S[0, 2], S[1, 0]], tr.nu[3:], atol=1e-7)


def test_plane_caster_distance_matches_geometry():
    caster = PlaneCaster([0.0, 0.0, 10.0], [0.0, 0.0, -1.0])
    d = np.array([[0.0, 0.0, 1.0], [np.sin(0.5), 0.0, np.cos(0.5)], [0.0, 0.0, -1.0]])
    hits = caster.cast(np.array([1.0, 2.0, 4.0]), d, 100.0)
    np.testing.assert_allclose(hits.dist_m[:2], [6.0, 6.0 / np.cos(0.5)])
    assert np.isinf(hits.dist_m[2]) and hits.object_id[2] == -2


def test_survey_positions_consistent_with_body_velocity():
    truths = survey_truths(dt_s=0.1, leg_s=20.0, n_legs=2, surface_s=5.0)
    for i in range(1, len(truths) - 1, 37):
        fd = (truths[i + 1].pos_ned - truths[i - 1].pos_ned) / 0.2
        np.testing.assert_allclose(truths[i].vel_ned_mps, fd, atol=2e-3)
