"""Kinematic trajectories and an analytic plane caster for the navigation tests (and checks of
them against independent finite differences / geometry)."""

from __future__ import annotations

import numpy as np

from tests.support import PlaneCaster, survey_truths, wiggle_truth

# ----------------------------------------------------------------------------- casters


# ----------------------------------------------------------------------------- trajectories


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
