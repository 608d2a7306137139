"""The DVL-free speed model against closed forms, and the navigation config that selects it."""

import math

import numpy as np
import pytest
from pydantic import ValidationError

from autonomy.navigation.config import NavigationConfig, SpeedModelConfig
from autonomy.navigation.speed_model import SpeedModel, steady_speed_mps

CFG = SpeedModelConfig(mass_kg=(19.86, 20.62), damping_linear=(13.7, 0.0), damping_quadratic=(141.0, 217.0))


def test_steady_speed_is_the_root_of_the_damping_balance():
    v = steady_speed_mps(10.0, 13.7, 141.0)
    assert 141.0 * v * v + 13.7 * v == pytest.approx(10.0)
    assert steady_speed_mps(-10.0, 13.7, 141.0) == pytest.approx(-v)
    assert steady_speed_mps(5.0, 10.0, 0.0) == pytest.approx(0.5)


def test_model_reaches_the_steady_speed_and_follows_the_linear_closed_form():
    m = SpeedModel(CFG)
    m.set_force([10.0, -4.0])
    for _ in range(3000):
        v = m.step(0.1)
    assert v[0] == pytest.approx(steady_speed_mps(10.0, 13.7, 141.0), rel=1e-9)
    assert v[1] == pytest.approx(steady_speed_mps(-4.0, 0.0, 217.0), rel=1e-9)
    # linear damping only: v(t) = F / d (1 - exp(-d t / m))
    lin = SpeedModel(SpeedModelConfig(mass_kg=(20.0, 20.0), damping_linear=(10.0, 10.0), damping_quadratic=(0.0, 0.0)))
    lin.set_force([5.0, 0.0])
    for _ in range(2000):
        v = lin.step(0.001)
    assert v[0] == pytest.approx(0.5 * (1 - math.exp(-10.0 * 2.0 / 20.0)), rel=1e-3)
    assert v[1] == 0.0


def test_speed_model_source_needs_its_block_and_sane_values():
    with pytest.raises(ValidationError, match="speed_model block"):
        NavigationConfig(velocity_source="speed_model")
    with pytest.raises(ValidationError, match="mass_kg must be > 0"):
        SpeedModelConfig(mass_kg=(0.0, 1.0), damping_linear=(1.0, 1.0), damping_quadratic=(0.0, 0.0))
    assert NavigationConfig(velocity_source="speed_model", speed_model=CFG).speed_model.mass_kg == (19.86, 20.62)


def test_dvl_free_filter_dead_reckons_with_the_model_along_the_heading():
    from autonomy.messages import ImuMsg, WrenchCmdMsg
    from autonomy.navigation.ekf import NavigationFilter
    from sim.sensors.nav_noise import nav_noise_model

    cfg = NavigationConfig(velocity_source="speed_model", speed_model=CFG)
    nf = NavigationFilter(cfg, np.zeros(3), 0.0, nav_noise_model())
    yaw = math.radians(30.0)
    nf.on_imu(ImuMsg(0.0, np.array([0.0, 0.0, yaw]), np.zeros(3), np.array([0.0, 0.0, -9.81])))
    nf.on_wrench_cmd(WrenchCmdMsg(0.0, np.array([10.0, 0.0, 0.0, 0.0, 0.0, 0.0])))
    t, p = 0.0, np.zeros(2)
    ref = SpeedModel(CFG)
    ref.set_force([10.0, 0.0])
    for _ in range(600):
        t += 0.1
        nf.predict(t)
        p += 0.1 * ref.step(0.1)[0] * np.array([math.cos(yaw), math.sin(yaw)])
    assert np.allclose(nf.estimate().pos_ned[:2], p, atol=1e-6)
