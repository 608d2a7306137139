"""INS drift model of paper 003 (Gaglione, Soldi, Braca, JAIF 2023, eqs. 28-30).

Navigation output ``g_t = [p_t, psi_t] + d_t`` (eq. 28): true horizontal position (NED
north, east, m) and heading, plus a 3-D Gaussian drift whose mean (eq. 29) and variance
(eq. 30) at elapsed time ``tau`` (hours) are, with ``u = psi_t + lambda_0``::

    mean = [ 0.5 eps_p tau^2 cos u,  0.5 eps_p tau^2 sin u,  (-1)^iota eps_h tau ]
    var  = [ vs_p^2 tau^3 cos^2 u / 3,  vs_p^2 tau^3 sin^2 u / 3,  vs_h^2 tau ]

The drift lives in the vehicle frame (``u`` turns with the heading): ``lambda_0 = 0`` puts
the INS ahead of the vehicle, ``pi`` behind. The paper gives marginals only; here the
random part is a smooth process with exactly those marginals: the position parts are
``cos u`` / ``sin u`` times an integrated Wiener process of intensity ``vs_p^2`` (variance
``vs_p^2 tau^3 / 3``), the heading part a Wiener process of intensity ``vs_h^2``, both sampled
exactly at the output times.

Units: ``eps_p`` m/h^2, ``eps_h`` deg/h, ``vs_p`` m/h^(3/2) (the paper writes m/h^2),
``vs_h`` deg/sqrt(h); times in seconds at the interface.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
S_PER_H = 3600.0


@dataclass(frozen=True)
class InsDriftParams:
    """Drift parameters (paper 003, Section V; REFERENCE: eps_p 7.5 m/h^2, eps_h 1 deg/h,
    vs_p 7.5, vs_h 0.6 deg/sqrt(h))."""

    eps_p_m_per_h2: float = 7.5
    eps_h_deg_per_h: float = 1.0
    varsigma_p: float = 7.5
    varsigma_h_deg_per_sqrt_h: float = 0.6

    def __post_init__(self) -> None:
        vals = (self.eps_p_m_per_h2, self.eps_h_deg_per_h, self.varsigma_p, self.varsigma_h_deg_per_sqrt_h)
        if not all(np.isfinite(v) and v >= 0.0 for v in vals):
            raise ValueError(f"INS drift parameters must be finite and >= 0, got {vals}")


def drift_mean(elapsed_s: ArrayLike, heading_rad: ArrayLike, lambda0_rad: float, iota: int,
               p: InsDriftParams = InsDriftParams()) -> FloatArray:
    """Eq. 29: mean drift (..., 3) = (north m, east m, heading rad) at ``elapsed_s`` (...) s and
    true heading ``heading_rad`` (...) (NED yaw)."""
    tau = np.asarray(elapsed_s, dtype=float) / S_PER_H
    u = np.asarray(heading_rad, dtype=float) + lambda0_rad
    a = 0.5 * p.eps_p_m_per_h2 * tau ** 2
    h = (-1.0) ** int(iota) * np.deg2rad(p.eps_h_deg_per_h) * tau
    return np.stack(np.broadcast_arrays(a * np.cos(u), a * np.sin(u), h), axis=-1)


def drift_variance(elapsed_s: ArrayLike, heading_rad: ArrayLike, lambda0_rad: float,
                   p: InsDriftParams = InsDriftParams()) -> FloatArray:
    """Eq. 30: drift variances (..., 3) (north m^2, east m^2, heading rad^2)."""
    tau = np.asarray(elapsed_s, dtype=float) / S_PER_H
    u = np.asarray(heading_rad, dtype=float) + lambda0_rad
    c = p.varsigma_p ** 2 * tau ** 3 / 3.0
    vh = np.deg2rad(p.varsigma_h_deg_per_sqrt_h) ** 2 * tau
    return np.stack(np.broadcast_arrays(c * np.cos(u) ** 2, c * np.sin(u) ** 2, vh), axis=-1)


def sample_drift(elapsed_s: ArrayLike, heading_rad: ArrayLike, rng: np.random.Generator,
                 p: InsDriftParams = InsDriftParams(), *, lambda0_rad: float | None = None,
                 iota: int | None = None, n_draws: int | None = None) -> tuple[FloatArray, float, int]:
    """Drift along one trajectory (or ``n_draws`` independent ones).

    Args:
        elapsed_s: (T,) increasing output times since the start (s, > 0 or the first may be 0).
        heading_rad: (T,) true heading at those times (NED yaw).
        rng: the drift's generator (``component_rng(seed, "ins")``).
        p: parameters.
        lambda0_rad, iota: drawn (uniform in (0, 2 pi), uniform in {0, 1}) when ``None``.
        n_draws: None for one trajectory (T, 3); else (n_draws, T, 3) sharing lambda_0 and iota.

    Returns:
        ``(d, lambda0_rad, iota)``: d (T, 3) or (n_draws, T, 3) = (north m, east m, heading rad).

    Raises:
        ValueError: times not increasing, negative, or shapes differ.
    """
    t = np.asarray(elapsed_s, dtype=float).reshape(-1)
    psi = np.broadcast_to(np.asarray(heading_rad, dtype=float), t.shape)
    if t.size == 0 or t[0] < 0.0 or np.any(np.diff(t) <= 0.0):
        raise ValueError("elapsed_s must be non-negative and strictly increasing")
    lam = float(rng.uniform(0.0, 2.0 * np.pi)) if lambda0_rad is None else float(lambda0_rad)
    io = int(rng.integers(0, 2)) if iota is None else int(iota)
    n = 1 if n_draws is None else int(n_draws)
    tau = t / S_PER_H
    dt = np.diff(np.concatenate([[0.0], tau]))
    # integrated Wiener process (W, I = int W) of unit intensity, exact transition per step
    z = rng.standard_normal((n, 2, t.size, 2))  # (draw, north/east, time, 2 normals)
    w = np.zeros((n, 2))
    i_ = np.zeros((n, 2))
    pos = np.empty((n, t.size, 2))
    for k in range(t.size):
        h = dt[k]
        # cov [[h, h^2/2], [h^2/2, h^3/3]]: Cholesky [[sqrt h, 0], [h^1.5/2, h^1.5/sqrt(12)]]
        e1, e2 = z[:, :, k, 0], z[:, :, k, 1]
        dw = np.sqrt(h) * e1
        di = h * w + h ** 1.5 * (0.5 * e1 + e2 / np.sqrt(12.0))
        w = w + dw
        i_ = i_ + di
        pos[:, k] = i_
    heading_walk = np.cumsum(np.sqrt(dt)[None, :] * rng.standard_normal((n, t.size)), axis=1)
    mean = drift_mean(t, psi, lam, io, p)
    u = psi + lam
    d = np.empty((n, t.size, 3))
    d[..., 0] = mean[:, 0] + p.varsigma_p * np.cos(u) * pos[..., 0]
    d[..., 1] = mean[:, 1] + p.varsigma_p * np.sin(u) * pos[..., 1]
    d[..., 2] = mean[:, 2] + np.deg2rad(p.varsigma_h_deg_per_sqrt_h) * heading_walk
    return (d[0] if n_draws is None else d), lam, io
