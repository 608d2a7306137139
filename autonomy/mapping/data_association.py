"""Loopy belief propagation for probabilistic data association (pure numpy).

The SPA association loop of paper 003 (Section IV, after Williams and Lau's BP for the
association posterior and Meyer et al.'s scalable multitarget tracking): with ``beta[k, 0]``
the weight of legacy object k being missed, ``beta[k, m]`` (m >= 1) of it generating
measurement m, and ``xi[m - 1]`` the weight of measurement m coming from a new object or
clutter, iterate in the log domain

    phi_{k->m} = beta[k, m] / (beta[k, 0] + sum_{m' != m} beta[k, m'] nu_{m'->k})
    nu_{m->k}  = 1 / (xi[m] + sum_{k' != k} phi_{k'->m})

from ``nu = 1`` until the largest change of a log-message is below ``tol`` (1e-5 in the paper).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class AssociationResult:
    """BP output.

    Attributes:
        nu: (K, M) messages measurement -> object, ``nu_{m->k}``.
        phi: (K, M) messages object -> measurement.
        p_object: (K, M + 1) association marginals of each object (column 0: missed).
        p_measurement_new: (M,) probability that each measurement is not from a legacy object.
        iterations: iterations run; converged: whether ``tol`` was met.
    """

    nu: FloatArray
    phi: FloatArray
    p_object: FloatArray
    p_measurement_new: FloatArray
    iterations: int
    converged: bool


def loopy_bp(beta: ArrayLike, xi: ArrayLike | None = None, *, tol: float = 1e-5,
             max_iter: int = 1000) -> AssociationResult:
    """Association marginals by loopy BP.

    Args:
        beta: (K, M + 1) non-negative weights, column 0 the miss weight (> 0).
        xi: (M,) positive weights of "new object or clutter" (default ones).
        tol: stop when the largest absolute change of ``log nu`` is below it.
        max_iter: iteration cap.

    Returns:
        :class:`AssociationResult`.

    Raises:
        ValueError: bad shapes, negative weights, a zero miss weight or a non-positive ``xi``.
    """
    b = np.asarray(beta, dtype=float)
    if b.ndim != 2 or b.shape[1] < 1:
        raise ValueError(f"beta must be (K, M + 1), got shape {b.shape}")
    k_n, m_n = b.shape[0], b.shape[1] - 1
    x = np.ones(m_n) if xi is None else np.asarray(xi, dtype=float).reshape(-1)
    if x.shape != (m_n,) or np.any(~(x > 0.0)):
        raise ValueError(f"xi must hold {m_n} positive weights")
    if np.any(~np.isfinite(b)) or np.any(b < 0.0) or np.any(~(b[:, 0] > 0.0)):
        raise ValueError("beta must be finite, non-negative, with positive miss weights")
    if k_n == 0 or m_n == 0:
        p_obj = np.zeros((k_n, m_n + 1))
        p_obj[:, 0] = 1.0
        return AssociationResult(np.ones((k_n, m_n)), np.zeros((k_n, m_n)), p_obj, np.ones(m_n), 0, True)
    b0, bm = b[:, :1], b[:, 1:]
    nu = np.ones((k_n, m_n))
    converged = False
    it = 0
    log_nu = np.zeros_like(nu)
    for it in range(1, max_iter + 1):
        s = bm * nu
        phi = bm / (b0 + s.sum(axis=1, keepdims=True) - s)
        tot = phi.sum(axis=0, keepdims=True)
        nu = 1.0 / (x[None, :] + tot - phi)
        new_log = np.log(nu)
        delta = float(np.max(np.abs(new_log - log_nu)))
        log_nu = new_log
        if delta < tol:
            converged = True
            break
    s = bm * nu
    phi = bm / (b0 + s.sum(axis=1, keepdims=True) - s)
    p_obj = np.concatenate([b0, s], axis=1)
    p_obj /= p_obj.sum(axis=1, keepdims=True)
    p_new = x / (x + phi.sum(axis=0))
    return AssociationResult(nu, phi, p_obj, p_new, it, converged)


def exact_marginals(beta: ArrayLike, xi: ArrayLike | None = None) -> FloatArray:
    """Exact association marginals (K, M + 1) by enumerating every one-to-one association.

    The joint weight of an association ``a`` (``a_k = 0`` missed, else its measurement, no
    measurement used twice) is ``prod_k beta[k, a_k] prod_{m unused} xi[m]``. Exponential in
    size: for tests and small problems only.

    Raises:
        ValueError: more than 8 objects or measurements.
    """
    b = np.asarray(beta, dtype=float)
    k_n, m_n = b.shape[0], b.shape[1] - 1
    if k_n > 8 or m_n > 8:
        raise ValueError("exact enumeration is limited to 8 objects and 8 measurements")
    x = np.ones(m_n) if xi is None else np.asarray(xi, dtype=float)
    out = np.zeros_like(b)

    def rec(k: int, used: frozenset[int], w: float, assign: list[int]) -> None:
        if k == k_n:
            total = w * float(np.prod([x[m] for m in range(m_n) if m not in used]))
            for kk, a in enumerate(assign):
                out[kk, a] += total
            return
        rec(k + 1, used, w * b[k, 0], assign + [0])
        for m in range(m_n):
            if m not in used and b[k, m + 1] > 0.0:
                rec(k + 1, used | {m}, w * b[k, m + 1], assign + [m + 1])

    rec(0, frozenset(), 1.0, [])
    return out / out.sum(axis=1, keepdims=True)
