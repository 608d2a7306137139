"""The surface buoy's 3-DOF dynamics against the 6-DOF reference model, the analytic
damping balance and an independent solve_ivp integration."""

from __future__ import annotations

import dataclasses
import math

import mujoco
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from autonomy.control.allocation import command_to_thrust, thrust_to_command
from autonomy.frames import rot_from_euler
from scenarios.config.world import CurrentConfig
from sim.dynamics.current import OceanCurrent
from sim.dynamics.hull import build_standalone_spec, build_hull_spec, VEHICLE_BODY
from sim.dynamics.hydrodynamics import acceleration
from sim.dynamics.surface_vessel import SurfaceVesselDynamics, horizontal_acceleration, horizontal_coefficients
from scenarios.vehicle_params import load_params_file, params_path

DT = 0.005


@pytest.fixture(scope="module")
def params():
    p = load_params_file(params_path("surface_buoy"))
    instant = np.zeros(p.layout.n)  # instantaneous rotors: steady thrust from the first step
    lay = dataclasses.replace(p.layout, dead_zone=instant.copy())
    return dataclasses.replace(p, thruster_time_constant_s=instant, layout=lay)


def make_sim(params, current=None, dt_s=DT):
    spec = mujoco.MjSpec()
    spec.option.gravity = [0.0, 0.0, 0.0]
    spec.option.timestep = dt_s
    spec.worldbody.add_frame().attach_body(build_hull_spec(params).body(VEHICLE_BODY), "buoy/", "")
    model = spec.compile()
    data = mujoco.MjData(model)
    bid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "buoy/vehicle")
    return model, data, SurfaceVesselDynamics(model, data, params, bid, current)


def test_preset_matches_paper_000_table_v(params):
    assert params.mass_kg == 37.0 and params.motion == "surface_3dof"
    np.testing.assert_allclose(params.envelope_m, [1.41, 0.535, 0.535])


def test_three_dof_model_is_the_six_dof_model_in_the_plane(params):
    """Rows u, v, r of Fossen's 6-DOF reference (sim.dynamics.hydrodynamics, matrix form) at w = p = q = 0,
    level, deep water: the 3-DOF equations must give the same accelerations."""
    rng = np.random.default_rng(4)
    for _ in range(20):
        u, v, r = rng.uniform(-0.7, 0.7), rng.uniform(-0.3, 0.3), rng.uniform(-0.5, 0.5)
        psi = rng.uniform(-math.pi, math.pi)
        cur = np.array([*rng.uniform(-0.3, 0.3, 2), 0.0])
        tau6 = np.array([rng.uniform(-15, 15), rng.uniform(-10, 10), 0.0, 0.0, 0.0, rng.uniform(-5, 5)])
        R = rot_from_euler(0.0, 0.0, psi)
        ref = acceleration(params, [u, v, 0, 0, 0, r], R, cur, tau6)[[0, 1, 5]]
        cb = R.T @ cur
        got = horizontal_acceleration(params, [u, v, r], cb[:2], tau6[[0, 1, 5]])
        np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-12)


def test_fast_path_matches_the_reference(params):
    model, data, dyn = make_sim(params, OceanCurrent(CurrentConfig(velocity_ned_mps=(0.1, -0.2, 0.0)), None))
    rng = np.random.default_rng(1)
    for _ in range(10):
        dyn.reset(rng.uniform(-5, 5, 2), rng.uniform(-3, 3))
        data.qvel[:3] = rng.uniform(-0.4, 0.4, 3)
        cmd = rng.uniform(-1, 1, params.layout.n)
        dyn.set_command(cmd)
        dyn.step_inputs(DT)
        t = dyn.truth(0.0)
        cb = t.R_nb.T @ np.array([0.1, -0.2, 0.0])
        tau = params.thruster_matrix @ command_to_thrust(cmd, params.layout)
        ref = horizontal_acceleration(params, t.nu[[0, 1, 5]], cb[:2], tau[[0, 1, 5]])
        np.testing.assert_allclose(t.nu_dot[[0, 1, 5]], ref, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("axis, cmd_sign", [(0, 1.0), (1, 1.0), (0, -1.0)])
def test_steady_speed_is_the_damping_balance(params, axis, cmd_sign):
    """Full thrust along surge or sway: MuJoCo settles at the speed where
    d_l U + d_q U^2 = thrust (Fossen's damping balance, solved analytically)."""
    model, data, dyn = make_sim(params)
    dyn.reset((0.0, 0.0), 0.0)
    B = params.thruster_matrix
    # Equal thrusts (within the smaller, reverse limit) signed along the axis: a pure force.
    thrust = cmd_sign * float(np.min(params.layout.max_rev_n)) * np.sign(B[axis])
    cmd = thrust_to_command(thrust, params.layout)
    dyn.set_command(cmd)
    for _ in range(int(60.0 / DT)):
        dyn.step_inputs(DT)
        mujoco.mj_step(model, data)
    force = float((B @ command_to_thrust(cmd, params.layout))[axis])
    c = horizontal_coefficients(params)
    dl, dq = c["linear"][axis], c["quadratic"][axis]
    speed = (-dl + math.sqrt(dl * dl + 4.0 * dq * abs(force))) / (2.0 * dq)
    t = dyn.truth(0.0)
    assert t.nu[axis] == pytest.approx(math.copysign(speed, force), rel=1e-4)
    assert abs(t.nu[1 - axis]) < 1e-6 and abs(t.nu[5]) < 1e-6
    if axis == 0 and cmd_sign > 0:  # all four at full forward thrust: the preset's top speed
        top = (-dl + math.sqrt(dl * dl + 4.0 * dq * float(B[0] @ params.layout.max_fwd_n))) / (2.0 * dq)
        assert 0.6 < top < 0.7  # ~0.65 m/s: twice paper 000's 0.3 m/s cruise, above its AUV's 0.5 m/s


def test_turning_trajectory_matches_solve_ivp(params):
    """A turning manoeuvre in a current: MuJoCo's integration of the joint forces against an
    adaptive solve_ivp of the 3-DOF kinematics + (independently written) matrix dynamics."""
    cur = np.array([0.1, 0.15, 0.0])
    model, data, dyn = make_sim(params, OceanCurrent(CurrentConfig(velocity_ned_mps=tuple(cur)), None))
    dyn.reset((0.0, 0.0), 0.3)
    cmd = np.array([0.9, 0.2, 0.6, 0.4])
    dyn.set_command(cmd)
    tau = params.thruster_matrix @ command_to_thrust(cmd, params.layout)
    c = horizontal_coefficients(params)
    M = np.diag(np.array(c["rigid"]) + np.array(c["added"]))
    m, xa, ya = c["rigid"][0], c["added"][0], c["added"][1]
    MA = np.diag(c["added"])

    def rhs(_t, y):
        n, e, psi, u, v, r = y
        R = np.array([[math.cos(psi), -math.sin(psi)], [math.sin(psi), math.cos(psi)]])
        uc, vc = R.T @ cur[:2]
        nr = np.array([u - uc, v - vc, r])
        Crb = np.array([[0, 0, -m * v], [0, 0, m * u], [m * v, -m * u, 0]])
        Ca = np.array([[0, 0, -ya * nr[1]], [0, 0, xa * nr[0]], [ya * nr[1], -xa * nr[0], 0]])
        D = np.diag(np.array(c["linear"]) + np.array(c["quadratic"]) * np.abs(nr))
        nucdot = np.array([r * vc, -r * uc, 0.0])
        nudot = np.linalg.solve(M, tau[[0, 1, 5]] - Crb @ [u, v, r] - Ca @ nr - D @ nr + MA @ nucdot)
        return [*(R @ [u, v]), r, *nudot]

    T = 40.0
    sol = solve_ivp(rhs, (0, T), [0, 0, 0.3, 0, 0, 0], rtol=1e-9, atol=1e-11, dense_output=True)
    for k in range(int(T / DT)):
        dyn.step_inputs(DT)
        mujoco.mj_step(model, data)
    ref = sol.sol(T)
    t = dyn.truth(T)
    travelled = float(np.hypot(*ref[:2]))
    assert travelled > 5.0
    assert np.hypot(*(t.pos_ned[:2] - ref[:2])) < 0.01 * travelled
    assert abs(math.remainder(t.rpy_rad[2] - ref[2], 2 * math.pi)) < 0.02


def test_free_6dof_presets_are_rejected(params):
    with pytest.raises(ValueError, match="not 'surface_3dof'"):
        horizontal_coefficients(load_params_file(params_path("feelhippo")))
    spec = build_standalone_spec(load_params_file(params_path("feelhippo")))
    model = spec.compile()
    with pytest.raises(ValueError, match="slides and a yaw hinge"):
        SurfaceVesselDynamics(model, mujoco.MjData(model), params, 1)
