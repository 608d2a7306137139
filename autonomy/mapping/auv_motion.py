"""Nearly-constant-turn (NCT) motion of the vehicle state particles (pure numpy).

State ``s = [north m, east m, v_north m/s, v_east m/s, turn rate rad/s]`` (NED horizontal;
heading ``atan2(v_east, v_north)``), paper 003 eq. 27 with the NCT model of Li and Jilkov
(Survey of maneuvering target tracking, part I, eqs. 6-7): over ``dt`` the velocity turns by
``omega dt``; the process noise is a linear acceleration along the heading and an angular
acceleration, ``diag(sigma_lin^2, sigma_ang^2)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def wrap_angle(a: FloatArray) -> FloatArray:
    """Angles (rad) wrapped into [-pi, pi)."""
    return (np.asarray(a) + np.pi) % (2.0 * np.pi) - np.pi


def heading_rad(states: FloatArray) -> FloatArray:
    """(N,) heading (NED yaw) of states (N, 5)."""
    return np.arctan2(states[:, 3], states[:, 2])


def nct_predict(states: FloatArray, dt_s: float, sigma_lin_mps2: float, sigma_ang_radps2: float,
                rng: np.random.Generator) -> FloatArray:
    """Propagate states (N, 5) by ``dt_s`` with NCT motion and its process noise; returns (N, 5)."""
    out = _ct_move(states, states[:, 4], dt_s)
    if sigma_lin_mps2 > 0.0 or sigma_ang_radps2 > 0.0:
        u = rng.standard_normal((len(states), 2)) * np.array([sigma_lin_mps2, sigma_ang_radps2])
        psi = heading_rad(out)
        cp, sp = np.cos(psi), np.sin(psi)
        out[:, 0] += 0.5 * dt_s ** 2 * cp * u[:, 0]
        out[:, 1] += 0.5 * dt_s ** 2 * sp * u[:, 0]
        out[:, 2] += dt_s * cp * u[:, 0]
        out[:, 3] += dt_s * sp * u[:, 0]
        out[:, 4] += dt_s * u[:, 1]
    return out


def _ct_move(states: FloatArray, turn_rate: FloatArray, dt_s: float) -> FloatArray:
    """Noise-free coordinated turn of states (N, 5) over ``dt_s`` at ``turn_rate`` (N,) rad/s."""
    n, e, vn, ve, _ = states.T
    wt = turn_rate * dt_s
    small = np.abs(wt) < 1e-6
    safe_w = np.where(small, 1.0, turn_rate)
    s_w = np.where(small, dt_s, np.sin(wt) / safe_w)
    c_w = np.where(small, 0.5 * turn_rate * dt_s ** 2, (1.0 - np.cos(wt)) / safe_w)
    c, s = np.cos(wt), np.sin(wt)
    return np.column_stack([n + s_w * vn - c_w * ve, e + c_w * vn + s_w * ve, c * vn - s * ve, s * vn + c * ve,
                            turn_rate])


def nct_predict_ins_proposal(states: FloatArray, dt_s: float, sigma_lin_mps2: float, sigma_ang_radps2: float,
                             g: FloatArray, var_pos_m2: float, var_heading_rad2: float,
                             rng: np.random.Generator) -> tuple[FloatArray, FloatArray]:
    """NCT prediction with the locally optimal proposal for one INS output (pure numpy).

    The process noise ``u = [u_lin, u_ang]`` is drawn from its posterior given the INS output
    ``g = [north, east, heading] + v`` (``var v = diag(var_pos, var_pos, var_heading)``) instead
    of its prior (Doucet, Godsill and Andrieu 2000, the optimal importance density): with the
    angular noise entering the turn rate at the start of the step, the new heading is
    ``psi + (omega + dt u_ang) dt``, linear in ``u_ang``; the linear noise acts along the new
    heading, ``p = p0 + dt^2/2 h u_lin``, linear in ``u_lin``. Both posteriors are Gaussian and
    exact (up to heading wrap and a speed that turns negative). The returned log-weights are the
    predictive likelihoods ``log p(g | s_{t-1})`` with the INS likelihood's own normalising
    constant left out (as a bootstrap filter's ``log f(g | s_t)`` would), so that the weighted
    particles represent the same posterior as the bootstrap filter (prior draw times
    likelihood) with far less degeneracy: with paper 003's process noise (20 deg/s^2 at 1 Hz) a
    prior draw puts the heading about 20 deg off and a 2 deg INS likelihood kills most particles.

    Args:
        states: (N, 5) ``[north, east, v_north, v_east, turn rate]`` at t - dt (NED, m, m/s, rad/s).
        dt_s: step, s (> 0).
        sigma_lin_mps2, sigma_ang_radps2: process noise std (paper 003 eq. 27).
        g: (3,) INS output at t (north m, east m, heading rad).
        var_pos_m2, var_heading_rad2: INS likelihood variances (> 0).
        rng: generator.

    Returns:
        ``(states_t, log_weight)``: (N, 5) and (N,).
    """
    d2 = dt_s * dt_s
    psi = heading_rad(states)
    # angular noise: heading_t = psi0 + dt^2 u_ang
    psi0 = psi + states[:, 4] * dt_s
    e_h = wrap_angle(g[2] - psi0)
    sa2 = sigma_ang_radps2 ** 2
    s_h = var_heading_rad2 + d2 * d2 * sa2
    u_ang = sa2 * d2 * e_h / s_h + np.sqrt(sa2 * var_heading_rad2 / s_h) * rng.standard_normal(len(states))
    out = _ct_move(states, states[:, 4] + dt_s * u_ang, dt_s)
    # linear noise along the new heading: p_t = p0 + dt^2/2 h u_lin, v_t = v0 + dt h u_lin
    hdg = heading_rad(out)
    h = np.column_stack([np.cos(hdg), np.sin(hdg)])
    e_p = g[:2] - out[:, :2]
    along = np.einsum("ij,ij->i", h, e_p)
    cross = h[:, 0] * e_p[:, 1] - h[:, 1] * e_p[:, 0]
    sl2, b = sigma_lin_mps2 ** 2, 0.5 * d2
    s_a = var_pos_m2 + b * b * sl2
    u_lin = sl2 * b * along / s_a + np.sqrt(sl2 * var_pos_m2 / s_a) * rng.standard_normal(len(states))
    out[:, :2] += (b * u_lin)[:, None] * h
    out[:, 2:4] += (dt_s * u_lin)[:, None] * h
    logw = -0.5 * (e_h * e_h / s_h + along * along / s_a + cross * cross / var_pos_m2
                   + np.log(s_h / var_heading_rad2) + np.log(s_a / var_pos_m2))
    # a draw that reverses the velocity turns the heading by pi, outside the linear model above:
    # weight it by its true heading likelihood (about zero, as the bootstrap filter would)
    flipped = np.einsum("ij,ij->i", out[:, 2:4], h) < 0.0
    if np.any(flipped):
        e_f = wrap_angle(g[2] - heading_rad(out[flipped]))
        logw[flipped] += -0.5 * e_f * e_f / var_heading_rad2
    return out, logw
