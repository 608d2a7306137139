"""NED/FRD -> ENU/FLU conversion (REP 103), checked against hand-derived cases and scipy."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from autonomy.frames import cov_enu_from_ned, enu_from_ned, flu_from_frd, quat_xyzw, rot_enu_flu, rot_from_euler


def test_world_axes():
    # north, east, down in ENU coordinates
    np.testing.assert_array_equal(enu_from_ned([1.0, 0.0, 0.0]), [0.0, 1.0, 0.0])
    np.testing.assert_array_equal(enu_from_ned([0.0, 1.0, 0.0]), [1.0, 0.0, 0.0])
    np.testing.assert_array_equal(enu_from_ned([0.0, 0.0, 1.0]), [0.0, 0.0, -1.0])
    np.testing.assert_array_equal(enu_from_ned([[3.0, 4.0, 5.0], [1.0, 2.0, 3.0]]), [[4.0, 3.0, -5.0], [2.0, 1.0, -3.0]])


def test_body_axes():
    np.testing.assert_array_equal(flu_from_frd([1.0, 2.0, 3.0]), [1.0, -2.0, -3.0])
    # an IMU at rest reads -g in FRD; ROS expects +g along z up
    np.testing.assert_allclose(flu_from_frd([0.0, 0.0, -9.81]), [0.0, 0.0, 9.81])


@pytest.mark.parametrize("yaw_ned_deg, forward_enu", [(0.0, (0, 1, 0)), (90.0, (1, 0, 0)), (180.0, (0, -1, 0)),
                                                      (-90.0, (-1, 0, 0))])
def test_heading(yaw_ned_deg, forward_enu):
    R = rot_enu_flu(rot_from_euler(0.0, 0.0, np.deg2rad(yaw_ned_deg)))
    np.testing.assert_allclose(R @ [1.0, 0.0, 0.0], forward_enu, atol=1e-15)
    np.testing.assert_allclose(R @ [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], atol=1e-15)  # body up is world up


def test_nose_up_and_starboard_down():
    # NED pitch > 0 is nose up: the FLU x axis gains +z in ENU
    R = rot_enu_flu(rot_from_euler(0.0, np.deg2rad(10.0), 0.0))
    assert (R @ [1.0, 0.0, 0.0])[2] == pytest.approx(np.sin(np.deg2rad(10.0)))
    # NED roll > 0 is starboard down: the FLU y (port) axis goes up
    R = rot_enu_flu(rot_from_euler(np.deg2rad(10.0), 0.0, 0.0))
    assert (R @ [0.0, 1.0, 0.0])[2] == pytest.approx(np.sin(np.deg2rad(10.0)))


def test_matches_enu_euler_angles_via_scipy():
    rng = np.random.default_rng(1)
    for roll, pitch, yaw in rng.uniform([-1, -1.2, -np.pi], [1, 1.2, np.pi], size=(50, 3)):
        R = rot_enu_flu(rot_from_euler(roll, pitch, yaw))
        # ENU/FLU Euler angles: same roll, opposite pitch, yaw measured from east anticlockwise
        ref = Rotation.from_euler("ZYX", [np.pi / 2 - yaw, -pitch, roll]).as_matrix()
        np.testing.assert_allclose(R, ref, atol=1e-12)
        assert np.linalg.det(R) == pytest.approx(1.0)


def test_covariance_and_quaternion_order():
    cov = np.array([[4.0, 1.0, 0.5], [1.0, 9.0, 0.2], [0.5, 0.2, 1.0]])
    out = cov_enu_from_ned(cov)
    np.testing.assert_allclose(np.diag(out), [9.0, 4.0, 1.0])
    assert out[0, 1] == 1.0 and out[0, 2] == -0.2 and out[1, 2] == -0.5
    np.testing.assert_array_equal(quat_xyzw([1.0, 2.0, 3.0, 4.0]), [2.0, 3.0, 4.0, 1.0])
