"""Circle fitting with outlier rejection: the algebraic fit and MLESAC of [P002] section 3.2.1.

Algebraic fit ([P002] eqs. 4-7): ``(x - a)^2 + (y - b)^2 = R^2`` rewritten as
``2 a x + 2 b y + (R^2 - a^2 - b^2) = x^2 + y^2``, linear in ``X = (2a, 2b, R^2 - a^2 - b^2)``:
rows ``A_i = [x_i, y_i, 1]``, ``b_i = x_i^2 + y_i^2``, ``X = argmin |A X - b|^2`` and
``a = X1 / 2``, ``b = X2 / 2``, ``R = sqrt(X3 + a^2 + b^2)``. The points are centred first
(the same solution, better conditioned).

MLESAC ([P002] Algorithm 1): ``N = log(p_fail) / log(1 - w^3)`` random 3-point models, each
scored with the cost ``C = sum_i min(e_i^2, T^2)``, ``e_i = | |p_i - (a, b)| - R |`` (the
truncated-quadratic likelihood cost of MLESAC as we read eqs. 8-10, which the source text
lost); the best model's inliers (``e_i < T``) are refitted with the algebraic fit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Circle:
    """A fitted circle: centre ``(a, b)`` and radius ``R`` (m, the points' frame), the inlier
    mask over the input points and the cost of the best 3-point model."""

    centre: FloatArray
    radius_m: float
    inliers: NDArray[np.bool_]
    cost: float


def fit_circle_algebraic(points: ArrayLike) -> tuple[FloatArray, float]:
    """Least-squares circle through (N, 2) points, N >= 3 ([P002] eqs. 4-7).

    Returns:
        ``(centre (2,), radius)``.

    Raises:
        ValueError: fewer than 3 points, or collinear / coincident points (rank < 3).
    """
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(p) < 3:
        raise ValueError(f"a circle needs at least 3 points, got {len(p)}")
    origin = p.mean(axis=0)
    q = p - origin
    A = np.column_stack([q, np.ones(len(q))])
    rhs = np.einsum("ij,ij->i", q, q)
    X, _, rank, _ = np.linalg.lstsq(A, rhs, rcond=None)
    if rank < 3:
        raise ValueError("points are collinear or coincident: no circle")
    a, b = 0.5 * X[0], 0.5 * X[1]
    r2 = X[2] + a * a + b * b
    if not r2 > 0.0:
        raise ValueError("degenerate circle fit")
    return np.array([a, b]) + origin, float(math.sqrt(r2))


def circle_residuals(points: ArrayLike, centre: ArrayLike, radius_m: float) -> FloatArray:
    """(N,) ``| |p - centre| - R |`` of (N, 2) points, m."""
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    return np.abs(np.hypot(p[:, 0] - centre[0], p[:, 1] - centre[1]) - radius_m)


def mlesac_iterations(failure_probability: float, inlier_proportion: float) -> int:
    """``ceil(log(p_fail) / log(1 - w^3))`` ([P002] Algorithm 1, line 2).

    Raises:
        ValueError: a probability outside (0, 1).
    """
    if not (0.0 < failure_probability < 1.0 and 0.0 < inlier_proportion < 1.0):
        raise ValueError("failure_probability and inlier_proportion must lie in (0, 1)")
    return int(math.ceil(math.log(failure_probability) / math.log(1.0 - inlier_proportion ** 3)))


def _circles_through(p1: FloatArray, p2: FloatArray, p3: FloatArray) -> tuple[FloatArray, FloatArray, NDArray]:
    """Circumcircles of K triples (each (K, 2)): centres (K, 2), radii (K,), valid mask (K,)."""
    d = 2.0 * (p1[:, 0] * (p2[:, 1] - p3[:, 1]) + p2[:, 0] * (p3[:, 1] - p1[:, 1]) + p3[:, 0] * (p1[:, 1] - p2[:, 1]))
    s1, s2, s3 = (np.einsum("ij,ij->i", p, p) for p in (p1, p2, p3))
    ok = np.abs(d) > 1e-12
    d = np.where(ok, d, 1.0)
    ux = (s1 * (p2[:, 1] - p3[:, 1]) + s2 * (p3[:, 1] - p1[:, 1]) + s3 * (p1[:, 1] - p2[:, 1])) / d
    uy = (s1 * (p3[:, 0] - p2[:, 0]) + s2 * (p1[:, 0] - p3[:, 0]) + s3 * (p2[:, 0] - p1[:, 0])) / d
    centre = np.column_stack([ux, uy])
    return centre, np.hypot(p1[:, 0] - ux, p1[:, 1] - uy), ok


def mlesac_circle(points: ArrayLike, threshold_m: float, failure_probability: float, inlier_proportion: float,
                  rng: np.random.Generator, *, radius_range_m: tuple[float, float] = (0.0, np.inf)) -> Circle | None:
    """Circle with outlier rejection, [P002] Algorithm 1.

    Args:
        points: (N, 2) points, m.
        threshold_m: ``T``, the inlier distance and cost cap, m.
        failure_probability: probability of never drawing an all-inlier triple.
        inlier_proportion: expected share ``w`` of inliers.
        rng: generator for the triples.
        radius_range_m: models with a radius outside it are not considered (a known pool
            radius narrows the search; default: any).

    Returns:
        The refitted circle, or None when fewer than 3 points or no model has 3 inliers.

    Raises:
        ValueError: a non-positive threshold or a probability outside (0, 1).
    """
    if not threshold_m > 0.0:
        raise ValueError(f"threshold_m must be > 0, got {threshold_m}")
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    n_iter = mlesac_iterations(failure_probability, inlier_proportion)
    if len(p) < 3:
        return None
    # Algorithm 1 lines 3-12, vectorised: all N models drawn, then scored
    idx = np.stack([rng.choice(len(p), 3, replace=False) for _ in range(n_iter)]) if len(p) < 64 else \
        _distinct_triples(rng, len(p), n_iter)
    centre, radius, ok = _circles_through(p[idx[:, 0]], p[idx[:, 1]], p[idx[:, 2]])
    ok &= (radius >= radius_range_m[0]) & (radius <= radius_range_m[1])
    if not ok.any():
        return None
    centre, radius = centre[ok], radius[ok]
    t2 = threshold_m * threshold_m
    best_c, best_k = np.inf, -1
    for start in range(0, len(radius), 256):  # chunks bound the (models x points) memory
        c, r = centre[start:start + 256], radius[start:start + 256]
        e = np.abs(np.hypot(p[None, :, 0] - c[:, 0:1], p[None, :, 1] - c[:, 1:2]) - r[:, None])
        cost = np.minimum(e * e, t2).sum(axis=1)
        k = int(np.argmin(cost))
        if cost[k] < best_c:
            best_c, best_k = float(cost[k]), start + k
    inl = circle_residuals(p, centre[best_k], radius[best_k]) < threshold_m
    if inl.sum() < 3:
        return None
    try:
        c2, r2 = fit_circle_algebraic(p[inl])
    except ValueError:
        return None
    return Circle(c2, r2, inl, best_c)


def _distinct_triples(rng: np.random.Generator, n: int, k: int) -> NDArray[np.intp]:
    """(k, 3) index triples with three distinct indices each (rejection of the rare repeats)."""
    out = rng.integers(0, n, size=(k, 3))
    while True:
        bad = (out[:, 0] == out[:, 1]) | (out[:, 0] == out[:, 2]) | (out[:, 1] == out[:, 2])
        if not bad.any():
            return out
        out[bad] = rng.integers(0, n, size=(int(bad.sum()), 3))
