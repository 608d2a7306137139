"""Fossen model (pure numpy): fast path vs matrix reference, and analytic properties."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from autonomy.frames import quat_from_euler, rot_from_euler, rot_from_quat
from scenarios.config.vehicle import VehicleConfig
from sim.dynamics import hydrodynamics as hd
from scenarios.vehicle_params import load_vehicle_params


def _full_matrix_params(munk_moments: bool = True):
    """FeelHippo with off-diagonal added mass, full damping, speed decay, CG off-axis."""
    p = load_vehicle_params(VehicleConfig(model="feelhippo"))
    rng = np.random.default_rng(7)
    A = rng.normal(scale=0.5, size=(6, 6))
    M_A = p.added_mass + 0.5 * (A + A.T) * 0.3
    assert np.all(np.linalg.eigvalsh(M_A) > 0)
    D_l = p.damping_linear + rng.normal(scale=0.4, size=(6, 6))
    D_q = p.damping_quadratic + np.abs(rng.normal(scale=0.4, size=(6, 6)))
    return dataclasses.replace(
        p, added_mass=M_A, damping_linear=D_l, damping_quadratic=D_q,
        damping_linear_decay_spm=np.array([2.0, 1.0, 0.0, 0.5, 0.0, 3.0]),
        r_bg_m=np.array([0.01, -0.02, 0.03]), r_bb_m=np.array([-0.01, 0.005, -0.02]),
        munk_moments=munk_moments)


@pytest.mark.parametrize("model", ["feelhippo", "remus100", "bluerov2_heavy", "full", "full_no_munk"])
def test_fast_path_matches_matrix_reference(model):
    if model.startswith("full"):
        p = _full_matrix_params(munk_moments=model == "full")
    else:
        p = load_vehicle_params(VehicleConfig(model=model))
    rng = np.random.default_rng(3)
    fm = hd.FossenModel(p)
    for k in range(20):
        quat = rng.normal(size=4)
        quat /= np.linalg.norm(quat)
        vel_w, omega = rng.normal(size=3), rng.normal(size=3)
        cur = rng.normal(scale=0.3, size=3) if k % 2 else None
        tau = rng.normal(scale=20.0, size=6)
        depth = [5.0, 0.1, -0.1, -1.0][k % 4]
        xfrc = np.array(fm.mujoco_wrench(quat.tolist(), vel_w.tolist(), omega.tolist(),
                                         None if cur is None else cur.tolist(), tau.tolist(), depth))
        R = rot_from_quat(quat)
        nu = np.concatenate([R.T @ vel_w, omega])
        nu_dot = hd.acceleration(p, nu, R, np.zeros(3) if cur is None else cur, tau, depth)
        np.testing.assert_allclose(fm.nu, nu, atol=1e-12)
        np.testing.assert_allclose(fm.nu_dot(), nu_dot, rtol=1e-10, atol=1e-10)
        w = hd.rigid_body_wrench(p, nu, nu_dot)
        torque_cg = w[3:] - np.cross(p.r_bg_m, w[:3])
        np.testing.assert_allclose(xfrc, np.concatenate([R @ w[:3], R @ torque_cg]), rtol=1e-10, atol=1e-9)


def test_coriolis_matrices_do_no_work():
    """nu^T C(nu) nu = 0 for any mass matrix (skew-symmetric parametrisation)."""
    p = _full_matrix_params()
    rng = np.random.default_rng(0)
    for M in (p.rigid_body_mass, p.added_mass):
        for _ in range(10):
            nu = rng.normal(size=6)
            assert abs(nu @ hd.coriolis_matrix(M, nu) @ nu) < 1e-10


def test_rigid_body_coriolis_equals_newton_euler():
    """C_RB(nu) nu from the matrix form equals the Newton-Euler terms about CO."""
    p = _full_matrix_params()
    rng = np.random.default_rng(1)
    m, rg, Io = p.mass_kg, p.r_bg_m, p.inertia_co_kgm2
    for _ in range(10):
        nu = rng.normal(size=6)
        v, w = nu[:3], nu[3:]
        force = m * (np.cross(w, v) + np.cross(w, np.cross(w, rg)))
        moment = np.cross(w, Io @ w) + m * np.cross(rg, np.cross(w, v))
        np.testing.assert_allclose(hd.coriolis_matrix(p.rigid_body_mass, nu) @ nu,
                                   np.concatenate([force, moment]), atol=1e-10)


def test_restoring_moment_is_metacentric():
    """Rolled by phi (W = B): K = -W BG sin(phi), no net force; surfaced: buoyancy lost."""
    p = load_vehicle_params(VehicleConfig(model="feelhippo", buoyancy_fraction=1.0))
    bg = p.r_bg_m[2] - p.r_bb_m[2]
    for phi in (0.1, 0.5, -0.8):
        g = hd.restoring_forces(p, rot_from_euler(phi, 0.0, 0.0))
        np.testing.assert_allclose(g[:3], 0.0, atol=1e-12)
        assert g[3] == pytest.approx(p.weight_n * bg * np.sin(phi), rel=1e-12)  # g = -tau
        g = hd.restoring_forces(p, rot_from_euler(0.0, phi, 0.0))
        assert g[4] == pytest.approx(p.weight_n * bg * np.sin(phi), rel=1e-12)
    h = p.hull.size_m[2]
    assert hd.submerged_fraction(p, 10.0) == 1.0
    assert hd.submerged_fraction(p, -h) == 0.0
    assert hd.submerged_fraction(p, 0.0) == pytest.approx(0.5)
    g = hd.restoring_forces(p, np.eye(3), depth_m=-h)
    assert g[2] == pytest.approx(-p.weight_n)  # out of the water: weight only (g = -tau)


def test_added_mass_enters_acceleration_exactly():
    """Surge force on a body with diagonal M_A and CG at CO: u_dot = F / (m + X_udot)."""
    p = load_vehicle_params(VehicleConfig(model="feelhippo", buoyancy_fraction=1.0))
    p = dataclasses.replace(p, r_bg_m=np.zeros(3), r_bb_m=np.zeros(3))
    F = 30.0
    nu_dot = hd.acceleration(p, np.zeros(6), np.eye(3), np.zeros(3), [F, 0, 0, 0, 0, 0])
    assert nu_dot[0] == pytest.approx(F / (p.mass_kg + p.added_mass[0, 0]), rel=1e-12)
    np.testing.assert_allclose(nu_dot[1:], 0.0, atol=1e-12)


def test_current_acts_through_relative_velocity():
    """Vehicle drifting with a uniform current feels no damping: nu_r = 0 gives nu_dot = 0."""
    p = load_vehicle_params(VehicleConfig(model="feelhippo", buoyancy_fraction=1.0))
    R = rot_from_quat(quat_from_euler(0.0, 0.0, 0.7))
    cur = np.array([0.3, -0.2, 0.0])
    nu = np.concatenate([R.T @ cur, np.zeros(3)])
    np.testing.assert_allclose(hd.acceleration(p, nu, R, cur, np.zeros(6)), 0.0, atol=1e-12)
    still = hd.acceleration(p, nu, R, np.zeros(3), np.zeros(6))
    assert np.linalg.norm(still[:3]) > 1e-3


def test_munk_moment_of_bare_hull():
    """Full C_A gives the Munk pitch moment: the force term -C_A nu_r has pitch component
    (A33 - A11) u w (turns the hull broadside, destabilising); zeroed entries remove it."""
    p = load_vehicle_params(VehicleConfig(model="remus100"))
    nu_r = np.array([1.5, 0.0, 0.1, 0.0, 0.0, 0.0])
    A = np.diag(p.added_mass)
    full = dataclasses.replace(p, munk_moments=True)
    assert (hd.added_mass_coriolis(full, nu_r) @ nu_r)[4] == pytest.approx(-(A[2] - A[0]) * 1.5 * 0.1)
    assert (hd.added_mass_coriolis(p, nu_r) @ nu_r)[4] == 0.0
