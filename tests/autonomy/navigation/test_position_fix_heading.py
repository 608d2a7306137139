"""A feature fix's heading error updates the heading bias state by the scalar Kalman gain."""

import math

import numpy as np
import pytest

from autonomy.messages import PositionFixMsg
from autonomy.navigation.config import NavigationConfig
from autonomy.navigation.ekf import NavigationFilter
from sim.sensors.nav_noise import nav_noise_model


def test_heading_error_of_a_fix_moves_the_heading_bias_by_the_kalman_gain():
    nf = NavigationFilter(NavigationConfig(), np.zeros(3), 0.0, nav_noise_model())
    p55 = nf.covariance[5, 5]  # uncorrelated with the position at the start
    var, err = math.radians(0.5) ** 2, math.radians(1.5)
    yaw0 = nf.estimate().rpy_rad[2]
    nf.on_position_fix(PositionFixMsg(0.0, np.zeros(2), 0.01 * np.eye(2), heading_err_rad=err, heading_var_rad2=var))
    gain = p55 / (p55 + var)
    assert nf.state[5] == pytest.approx(gain * err, rel=1e-9)
    assert nf.covariance[5, 5] == pytest.approx(p55 * var / (p55 + var), rel=1e-9)
    assert nf.estimate().rpy_rad[2] == pytest.approx(yaw0 - gain * err, rel=1e-9)  # estimate turned towards truth
    before = nf.state
    nf.on_position_fix(PositionFixMsg(0.0, np.zeros(2), 0.01 * np.eye(2)))  # no heading: bias untouched
    assert nf.state[5] == before[5]
