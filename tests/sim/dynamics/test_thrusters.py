"""Thruster curves, rotor lag and thrust allocation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import lsq_linear

from autonomy.control.allocation import (
    allocate,
    allocate_thrust,
    command_to_thrust,
    thrust_to_command,
)
from scenarios.config.vehicle import ThrusterOverrides, VehicleConfig
from sim.dynamics.thrusters import ThrusterArray
from scenarios.vehicle_params import load_vehicle_params


@pytest.fixture(scope="module")
def feelhippo():
    return load_vehicle_params(VehicleConfig(model="feelhippo"))


def test_curve_dead_zone_saturation_and_asymmetry(feelhippo):
    lay = feelhippo.layout
    dz = lay.dead_zone[0]
    f = command_to_thrust([0.5 * dz, -0.5 * dz, 1.0, -1.0], lay)
    assert f[0] == 0.0 and f[1] == 0.0
    assert f[2] == pytest.approx(lay.max_fwd_n[2]) and f[3] == pytest.approx(-lay.max_rev_n[3])
    assert lay.max_fwd_n[0] != lay.max_rev_n[0]
    # Saturation: commands beyond +-1 give the limits.
    np.testing.assert_allclose(command_to_thrust([3.0, -3.0, 1.0, -1.0], lay),
                               [lay.max_fwd_n[0], -lay.max_rev_n[1], lay.max_fwd_n[2], -lay.max_rev_n[3]])
    # Curve: s = (c - dz) / (1 - dz), f = max * s^p.
    c = 0.6
    s = (c - dz) / (1 - dz)
    assert command_to_thrust([c] * 4, lay)[0] == pytest.approx(lay.max_fwd_n[0] * s ** lay.curve_exponent[0])


def test_thrust_to_command_inverts_curve(feelhippo):
    lay = feelhippo.layout
    rng = np.random.default_rng(0)
    f = rng.uniform(-lay.max_rev_n, lay.max_fwd_n, size=(50, lay.n))
    for row in f:
        np.testing.assert_allclose(command_to_thrust(thrust_to_command(row, lay), lay), row, atol=1e-9)
    assert np.all(thrust_to_command(np.zeros(lay.n), lay) == 0.0)


def test_rotor_lag_is_exact_first_order(feelhippo):
    thr = ThrusterArray(feelhippo)
    T = feelhippo.thruster_time_constant_s[0]
    dt = 0.005
    cmd = [1.0, 0.0, 0.0, 0.0]
    for k in range(1, 101):
        thr.step(cmd, dt)
        assert thr.speed[0] == pytest.approx(1.0 - math.exp(-k * dt / T), rel=1e-9)
    # The wrench uses the lagged thrust: surge = thrust, yaw = -y * thrust for +x thrust.
    tau = thr.step(cmd, dt)
    f = thr.thrust_n[0]
    y = feelhippo.layout.pos_body_m[0, 1]
    assert tau[0] == pytest.approx(f) and tau[5] == pytest.approx(-y * f)
    with pytest.raises(ValueError, match="4 values"):
        thr.step([0.0, 0.0], dt)
    with pytest.raises(ValueError, match="sway.*NaN"):
        thr.step([0.0, 0.0, float("nan"), 0.0], dt)


def test_zero_time_constant_is_instantaneous():
    p = load_vehicle_params(VehicleConfig(thrusters=ThrusterOverrides(time_constant_s=0.0)))
    thr = ThrusterArray(p)
    thr.step([0.7, -0.7, 0.2, 0.0], 0.005)
    np.testing.assert_allclose(thr.thrust_n, thr.steady_thrust([0.7, -0.7, 0.2, 0.0]))


@pytest.mark.parametrize("model", ["feelhippo", "bluerov2_heavy"])
def test_allocation_reproduces_achievable_wrenches(model):
    p = load_vehicle_params(VehicleConfig(model=model))
    lay = p.layout
    B = lay.config_matrix()
    rng = np.random.default_rng(1)
    for _ in range(20):
        f_true = rng.uniform(-0.5 * lay.max_rev_n, 0.5 * lay.max_fwd_n)
        tau = B @ f_true  # achievable by construction
        f = allocate_thrust(tau, B, -lay.max_rev_n, lay.max_fwd_n)
        np.testing.assert_allclose(B @ f, tau, atol=1e-9)
        cmd = allocate(tau, lay)
        assert np.all(np.abs(cmd) <= 1.0)
        np.testing.assert_allclose(B @ command_to_thrust(cmd, lay), tau, atol=1e-8)


def test_allocation_unachievable_dofs_least_squares(feelhippo):
    """FeelHippo cannot roll/pitch: those components are dropped, the rest matched."""
    lay = feelhippo.layout
    B = lay.config_matrix()
    tau = np.array([10.0, 3.0, -5.0, 2.0, 1.0, 1.5])
    f = allocate_thrust(tau, B, -lay.max_rev_n, lay.max_fwd_n)
    ref = lsq_linear(B, tau).x
    np.testing.assert_allclose(B @ f, B @ ref, atol=1e-8)


@pytest.mark.parametrize("model", ["feelhippo", "bluerov2_heavy"])
def test_allocation_saturation_close_to_bounded_least_squares(model):
    """Saturating requests stay within limits and leave (nearly) the residual of the
    optimal bounded least-squares solution (scipy lsq_linear as the oracle)."""
    p = load_vehicle_params(VehicleConfig(model=model))
    lay = p.layout
    B = lay.config_matrix()
    lo, hi = -lay.max_rev_n, lay.max_fwd_n
    rng = np.random.default_rng(2)
    worse = []
    for _ in range(40):
        tau = B @ rng.uniform(2.0 * lo, 2.0 * hi)
        f = allocate_thrust(tau, B, lo, hi)
        assert np.all(f >= lo - 1e-9) and np.all(f <= hi + 1e-9)
        best = lsq_linear(B, tau, bounds=(lo, hi)).x
        r_ours, r_best = np.linalg.norm(B @ f - tau), np.linalg.norm(B @ best - tau)
        assert r_ours <= 1.25 * r_best + 1e-6
        worse.append(r_ours / max(r_best, 1e-9))
    assert np.median(worse) < 1.02


def test_allocation_surge_saturation_keeps_yaw(feelhippo):
    """Asking for more surge than available with zero yaw moment: both surge thrusters at
    their limit, no yaw moment created."""
    lay = feelhippo.layout
    B = lay.config_matrix()
    f = allocate_thrust([500.0, 0, 0, 0, 0, 0], B, -lay.max_rev_n, lay.max_fwd_n)
    assert (B @ f)[0] == pytest.approx(lay.max_fwd_n[0] + lay.max_fwd_n[1])
    assert abs((B @ f)[5]) < 1e-9


def test_thrust_allocator_object_matches_function(feelhippo):
    from autonomy.control.allocation import ThrustAllocator

    wrench = np.array([30.0, 5.0, -8.0, 0.0, 0.0, 4.0])
    alloc = ThrustAllocator(feelhippo.thruster_matrix, feelhippo.thruster_limits_n, feelhippo.layout)
    np.testing.assert_allclose(alloc.allocate(wrench), allocate(wrench, feelhippo.layout))
    np.testing.assert_allclose(ThrustAllocator.from_layout(feelhippo.layout).allocate(wrench),
                               ThrusterArray(feelhippo).allocate(wrench))
    with pytest.raises(ValueError, match="command curves"):
        ThrustAllocator(feelhippo.thruster_matrix, feelhippo.thruster_limits_n).allocate(wrench)


def test_rotor_lag_follows_a_changed_command_after_a_held_one(feelhippo):
    """The speed targets are cached while the command is held: a new command (a new array,
    or the same array changed in place) must move the rotors towards the new target."""
    thr = ThrusterArray(feelhippo)
    T = feelhippo.thruster_time_constant_s[0]
    dz = feelhippo.layout.dead_zone[0]
    dt = 0.005
    cmd = np.array([1.0, 0.0, 0.0, 0.0])
    for _ in range(20):
        thr.step(cmd, dt)
    s0 = thr.speed[0]
    cmd[0] = -0.5  # changed in place
    target = -(0.5 - dz) / (1.0 - dz)
    for k in range(1, 21):
        thr.step(cmd, dt)
        assert thr.speed[0] == pytest.approx(target + (s0 - target) * math.exp(-k * dt / T), rel=1e-9)
    with pytest.raises(ValueError, match="NaN"):
        thr.step(np.array([-0.5, float("nan"), 0.0, 0.0]), dt)
    with pytest.raises(ValueError, match="NaN"):  # still refused when repeated
        thr.step(np.array([-0.5, float("nan"), 0.0, 0.0]), dt)


def test_weighted_allocator_object_matches_function_bit_for_bit(feelhippo):
    from autonomy.control.allocation import ThrustAllocator

    weights = np.array([1.0, 2.0, 4.0, 0.5, 0.5, 3.0])
    alloc = ThrustAllocator(feelhippo.thruster_matrix, feelhippo.thruster_limits_n, feelhippo.layout, weights)
    lim = feelhippo.thruster_limits_n
    for wrench in ([30.0, 5.0, -8.0, 0.0, 0.0, 4.0], [400.0, -90.0, 60.0, 1.0, -2.0, 50.0]):
        np.testing.assert_array_equal(alloc.allocate_thrust(wrench),
                                      allocate_thrust(wrench, feelhippo.thruster_matrix, lim[:, 0], lim[:, 1],
                                                      weights))
