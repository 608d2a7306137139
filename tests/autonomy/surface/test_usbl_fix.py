"""The buoy's USBL fix of the AUV: exact on noise-free geometry, and its first-order
covariance against a Monte Carlo of the USBL, compass and GNSS noise."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.frames import rot_from_euler, rot_z
from autonomy.surface.usbl_fix import usbl_fix_ned

MOUNT = np.array([0.2, -0.1, 0.4])
MOUNT_RPY = np.radians([0.0, 0.0, 30.0])
BUOY = np.array([3.0, -2.0, 0.0])
AUV = np.array([-1.0, 4.0, 2.3])


def _rbe(buoy, heading, auv):
    """Range, bearing, elevation of ``auv`` in the head frame, written out independently."""
    head = buoy + rot_z(heading) @ MOUNT
    d = rot_from_euler(*MOUNT_RPY).T @ rot_z(heading).T @ (auv - head)
    return np.array([np.linalg.norm(d), math.atan2(d[1], d[0]), math.atan2(d[2], math.hypot(d[0], d[1]))])


def test_noise_free_fix_is_the_transponder():
    for heading in (-2.5, 0.0, 0.7, 3.0):
        pos, cov = usbl_fix_ned(_rbe(BUOY, heading, AUV), BUOY, np.zeros((2, 2)), heading, mount_pos_body_m=MOUNT,
                                mount_rpy_rad=MOUNT_RPY, range_sigma_m=0.0, angle_sigma_rad=0.0,
                                heading_sigma_rad=0.0)
        np.testing.assert_allclose(pos, AUV, atol=1e-12)
        np.testing.assert_allclose(cov, 0.0, atol=1e-15)


def test_covariance_matches_monte_carlo():
    rng = np.random.default_rng(4)
    heading = 0.9
    sr, sa, sh, sg = 0.12, math.radians(1.0), math.radians(1.1), 0.5
    z0 = _rbe(BUOY, heading, AUV)
    _, cov = usbl_fix_ned(z0, BUOY, sg**2 * np.eye(2), heading, mount_pos_body_m=MOUNT, mount_rpy_rad=MOUNT_RPY,
                          range_sigma_m=sr, angle_sigma_rad=sa, heading_sigma_rad=sh)
    n = 20000
    pts = np.empty((n, 3))
    for i in range(n):
        z = z0 + rng.normal(0.0, [sr, sa, sa])
        h = heading + rng.normal(0.0, sh)
        b = BUOY + np.r_[rng.normal(0.0, sg, 2), 0.0]
        pts[i] = usbl_fix_ned(z, b, np.zeros((2, 2)), h, mount_pos_body_m=MOUNT, mount_rpy_rad=MOUNT_RPY,
                              range_sigma_m=0.0, angle_sigma_rad=0.0, heading_sigma_rad=0.0)[0]
    mc = np.cov(pts.T)
    # sample covariance of 20000 draws: ~1 % per element, plus the (small) linearisation error
    np.testing.assert_allclose(np.diag(cov), np.diag(mc), rtol=0.05)
    np.testing.assert_allclose(cov, mc, atol=0.05 * np.max(np.diag(mc)))
    np.testing.assert_allclose(pts.mean(axis=0), AUV, atol=0.02)


def test_bad_range_raises():
    with pytest.raises(ValueError, match="range"):
        usbl_fix_ned([float("nan"), 0.0, 0.0], BUOY, np.zeros((2, 2)), 0.0, mount_pos_body_m=MOUNT,
                     range_sigma_m=0.1, angle_sigma_rad=0.01, heading_sigma_rad=0.01)
