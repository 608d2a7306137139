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
    return _ct_move_columns(states[:, 0], states[:, 1], states[:, 2], states[:, 3], turn_rate, dt_s).T


def _ct_move_columns(north: FloatArray, east: FloatArray, v_n: FloatArray, v_e: FloatArray, turn: FloatArray,
                     dt_s: float) -> FloatArray:
    """Noise-free coordinated turn (Li and Jilkov eq. 6) of states given by component (each
    (N,)) over ``dt_s`` at ``turn`` (N,) rad/s; returns the new states (5, N)."""
    wt = turn * dt_s
    sin_wt, cos_wt = np.sin(wt), np.cos(wt)
    small = np.abs(wt) < 1e-6
    if small.any():
        safe = np.where(small, 1.0, turn)
        s_w = np.where(small, dt_s, sin_wt / safe)
        c_w = np.where(small, 0.5 * turn * dt_s ** 2, (1.0 - cos_wt) / safe)
    else:
        s_w = sin_wt / turn
        c_w = (1.0 - cos_wt) / turn
    new = np.empty((5, len(north)))
    new[0] = north + s_w * v_n - c_w * v_e
    new[1] = east + c_w * v_n + s_w * v_e
    new[2] = cos_wt * v_n - sin_wt * v_e
    new[3] = sin_wt * v_n + cos_wt * v_e
    new[4] = turn
    return new


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
    new, logw = ins_proposal_columns(np.asarray(states, dtype=float).T, dt_s, sigma_lin_mps2, sigma_ang_radps2,
                                     g, var_pos_m2, var_heading_rad2, rng)
    return new.T, logw


def ins_proposal_columns(cols: FloatArray, dt_s: float, sigma_lin_mps2: float, sigma_ang_radps2: float,
                         g: FloatArray, var_pos_m2: float, var_heading_rad2: float,
                         rng: np.random.Generator) -> tuple[FloatArray, FloatArray]:
    """:func:`nct_predict_ins_proposal` on the states stored by component, ``cols`` (5, N) (any
    strides, e.g. the transpose of an (N, 5) array); returns ``(new (5, N), log_weight (N,))``.

    The same algebra and the same draws (one (2, N) standard-normal block: the angular noises,
    then the linear ones, as two successive (N,) draws would give), written with few numpy
    calls, since at N of a few thousand the per-call overhead, not the arithmetic, sets the
    cost of the per-second filter.
    """
    north, east, v_n, v_e, rate = cols
    d2 = dt_s * dt_s
    sa2 = sigma_ang_radps2 ** 2
    s_h = var_heading_rad2 + d2 * d2 * sa2
    # angular noise: heading_t = psi + omega dt + dt^2 u_ang; innovation e_h against the INS heading
    e_h = rate * dt_s
    e_h += np.arctan2(v_e, v_n)
    np.subtract(g[2] + np.pi, e_h, out=e_h)
    np.remainder(e_h, 2.0 * np.pi, out=e_h)
    e_h -= np.pi
    z = rng.standard_normal((2, len(north)))
    turn = z[0] * np.sqrt(sa2 * var_heading_rad2 / s_h)
    turn += (sa2 * d2 / s_h) * e_h
    turn *= dt_s
    turn += rate  # the turn rate over the step, omega + dt u_ang
    new = _ct_move_columns(north, east, v_n, v_e, turn, dt_s)  # noise-free turn at that rate
    # linear noise along the new heading h: p_t = p0 + dt^2/2 h u_lin, v_t = v0 + dt h u_lin
    speed = np.hypot(new[2], new[3])
    moving = speed > 0.0
    h_n = np.divide(new[2], speed, out=np.ones_like(speed), where=moving)  # heading 0 when at rest
    h_e = np.divide(new[3], speed, out=np.zeros_like(speed), where=moving)
    e_n, e_e = g[0] - new[0], g[1] - new[1]
    along = h_n * e_n + h_e * e_e
    cross = h_n * e_e - h_e * e_n
    sl2, b = sigma_lin_mps2 ** 2, 0.5 * d2
    s_a = var_pos_m2 + b * b * sl2
    u_lin = z[1] * np.sqrt(sl2 * var_pos_m2 / s_a)
    u_lin += (sl2 * b / s_a) * along
    step = b * u_lin
    new[0] += step * h_n
    new[1] += step * h_e
    step = dt_s * u_lin
    new[2] += step * h_n
    new[3] += step * h_e
    e_h *= e_h
    e_h *= -0.5 / s_h
    along *= along
    e_h -= (0.5 / s_a) * along
    cross *= cross
    e_h -= (0.5 / var_pos_m2) * cross
    logw = e_h
    logw -= 0.5 * (np.log(s_h / var_heading_rad2) + np.log(s_a / var_pos_m2))
    # a draw that reverses the velocity (speed + dt u_lin < 0) turns the heading by pi, outside
    # the linear model above: weight it by its true heading likelihood (about zero, as the
    # bootstrap filter would)
    step += speed
    flipped = step < 0.0
    if flipped.any():
        e_f = wrap_angle(g[2] - np.arctan2(new[3, flipped], new[2, flipped]))
        logw[flipped] += -0.5 * e_f * e_f / var_heading_rad2
    return new, logw
