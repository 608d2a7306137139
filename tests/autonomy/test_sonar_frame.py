"""The sonar frame against hand-computed vectors and rotations."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.sonar_frame import (
    mount_euler_zyx,
    ray_directions_sonar,
    sonar_to_body_rotation,
    sonar_to_spherical,
    spherical_to_sonar,
)

S = np.sqrt(0.5)


@pytest.mark.parametrize(("az_deg", "el_deg", "want"), [
    (0.0, 0.0, [1.0, 0.0, 0.0]),            # boresight
    (90.0, 0.0, [0.0, 1.0, 0.0]),           # starboard
    (-90.0, 0.0, [0.0, -1.0, 0.0]),         # port
    (0.0, 90.0, [0.0, 0.0, 1.0]),           # straight down
    (0.0, -30.0, [np.sqrt(3) / 2, 0.0, -0.5]),  # up
    (45.0, 45.0, [0.5, 0.5, S]),
    (-45.0, 30.0, [np.sqrt(3) / 2 * S, -np.sqrt(3) / 2 * S, 0.5]),
])
def test_ray_directions_are_the_hand_computed_vectors(az_deg, el_deg, want):
    got = ray_directions_sonar(np.deg2rad(az_deg), np.deg2rad(el_deg))
    np.testing.assert_allclose(got, want, atol=1e-15)


def test_ray_directions_broadcast_and_are_unit():
    az, el = np.meshgrid(np.linspace(-1.1, 1.1, 7), np.linspace(-0.2, 0.2, 5), indexing="ij")
    d = ray_directions_sonar(az, el)
    assert d.shape == (7, 5, 3)
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0, atol=1e-15)


@pytest.mark.parametrize(("mount_deg", "boresight_body", "starboard_body"), [
    ((0.0, 0.0, 0.0), [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
    ((0.0, 30.0, 0.0), [np.sqrt(3) / 2, 0.0, 0.5], [0.0, 1.0, 0.0]),      # tilted down: boresight below x
    ((0.0, -30.0, 0.0), [np.sqrt(3) / 2, 0.0, -0.5], [0.0, 1.0, 0.0]),    # tilted up
    ((0.0, 20.0, 90.0), [0.0, np.cos(np.deg2rad(20)), np.sin(np.deg2rad(20))], [-1.0, 0.0, 0.0]),  # side-scan, stbd
    ((0.0, 20.0, -90.0), [0.0, -np.cos(np.deg2rad(20)), np.sin(np.deg2rad(20))], [1.0, 0.0, 0.0]),  # port
    ((90.0, 0.0, 0.0), [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),                 # rolled: sonar y points down
])
def test_mount_rotation_puts_the_axes_where_expected(mount_deg, boresight_body, starboard_body):
    R_bs = sonar_to_body_rotation(np.deg2rad(mount_deg))
    np.testing.assert_allclose(R_bs @ [1.0, 0.0, 0.0], boresight_body, atol=1e-15)
    np.testing.assert_allclose(R_bs @ [0.0, 1.0, 0.0], starboard_body, atol=1e-15)
    np.testing.assert_allclose(R_bs @ R_bs.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(R_bs) == pytest.approx(1.0)


def test_mount_euler_flips_only_the_tilt_and_batches():
    m = np.array([[0.1, 0.2, 0.3], [-0.4, -0.5, 0.6]])
    np.testing.assert_array_equal(mount_euler_zyx(m), [[0.1, -0.2, 0.3], [-0.4, 0.5, 0.6]])
    with pytest.raises(ValueError, match="shape"):
        mount_euler_zyx([0.1, 0.2])
    with pytest.raises(ValueError, match="shape"):
        sonar_to_body_rotation(m)


def test_spherical_round_trip(rng):
    r = rng.uniform(0.5, 100.0, 50)
    a = rng.uniform(-np.pi + 0.01, np.pi - 0.01, 50)
    e = rng.uniform(-1.5, 1.5, 50)
    p = spherical_to_sonar(r, a, e)
    np.testing.assert_allclose(np.linalg.norm(p, axis=1), r, rtol=1e-14)
    r2, a2, e2 = sonar_to_spherical(p)
    np.testing.assert_allclose(r2, r, rtol=1e-14)
    np.testing.assert_allclose(a2, a, atol=1e-12)
    np.testing.assert_allclose(e2, e, atol=1e-12)
