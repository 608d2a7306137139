"""World-model scoring against ground truth: optimal matching and GOSPA (pure numpy/scipy).

GOSPA (Rahmathullah, Garcia-Fernandez, Svensson 2017) with alpha = 2:
``d = [min over assignments sum min(d_ij, c)^p + (c^p / 2)(missed + false)]^(1/p)``.
A pair farther apart than ``c`` costs the same as leaving both unassigned, so the optimum
is one rectangular assignment on ``min(d, c)^p`` plus ``c^p / 2`` per unpaired point.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linear_sum_assignment

FloatArray = NDArray[np.float64]


def _points(x: ArrayLike, name: str) -> FloatArray:
    a = np.asarray(x, dtype=float)
    if a.size == 0:
        return a.reshape(0, a.shape[-1] if a.ndim == 2 else 0)
    if a.ndim != 2:
        raise ValueError(f"{name} must be an (N, d) array of points, got shape {a.shape}")
    return a


def _distances(est: FloatArray, truth: FloatArray) -> FloatArray:
    if est.shape[0] and truth.shape[0] and est.shape[1] != truth.shape[1]:
        raise ValueError(f"estimate dim {est.shape[1]} != truth dim {truth.shape[1]}")
    if not (est.shape[0] and truth.shape[0]):
        return np.zeros((est.shape[0], truth.shape[0]))
    return np.linalg.norm(est[:, None, :] - truth[None, :, :], axis=-1)


def gospa(estimates: ArrayLike, truths: ArrayLike, *, c: float, p: float = 1.0) -> float:
    """GOSPA distance (alpha = 2) between point sets (N, d) and (M, d)."""
    if c <= 0.0 or p < 1.0:
        raise ValueError(f"gospa needs c > 0 and p >= 1, got c={c}, p={p}")
    est, tru = _points(estimates, "estimates"), _points(truths, "truths")
    n, m = est.shape[0], tru.shape[0]
    total = 0.5 * c**p * abs(n - m)
    if n and m:
        cost = np.minimum(_distances(est, tru), c) ** p
        rows, cols = linear_sum_assignment(cost)
        total += float(cost[rows, cols].sum())
    return float(total ** (1.0 / p))


def match(
    estimates: ArrayLike, truths: ArrayLike, *, max_dist_m: float = 2.0
) -> list[tuple[int, int, float]]:
    """Optimal one-to-one matching within ``max_dist_m``: (est index, truth index, distance).

    Minimises the summed distance over pairs closer than the gate while maximising their
    number (pairs beyond the gate are never matched).
    """
    est, tru = _points(estimates, "estimates"), _points(truths, "truths")
    if not (est.shape[0] and tru.shape[0]):
        return []
    d = _distances(est, tru)
    big = 1e6 * (1.0 + max_dist_m)  # any gated pair beats any non-pair
    cost = np.where(d <= max_dist_m, d - big, 0.0)
    rows, cols = linear_sum_assignment(cost)
    return [(int(i), int(j), float(d[i, j])) for i, j in zip(rows, cols) if d[i, j] <= max_dist_m]


def score_world_model(
    estimates_ned: ArrayLike,
    truths_ned: ArrayLike,
    *,
    match_radius_m: float = 2.0,
    gospa_c_m: float = 2.0,
    gospa_p: float = 1.0,
    horizontal: bool = True,
) -> dict:
    """Metrics of estimated object positions (N, 3) against true ones (M, 3).

    ``horizontal`` compares north/east only (seabed objects: the estimate lies on the
    imaged surface, the truth is a centroid). Returns ``objects, matched, missed, false,
    mean_position_error_m`` (NaN when nothing matched), ``gospa``, and the matched pairs.
    """
    est, tru = _points(estimates_ned, "estimates_ned"), _points(truths_ned, "truths_ned")
    if horizontal:
        est, tru = est[:, :2], tru[:, :2]
    pairs = match(est, tru, max_dist_m=match_radius_m)
    errors = [d for _, _, d in pairs]
    return {
        "objects": int(est.shape[0]),
        "matched": len(pairs),
        "missed": int(tru.shape[0]) - len(pairs),
        "false": int(est.shape[0]) - len(pairs),
        "mean_position_error_m": float(np.mean(errors)) if errors else float("nan"),
        "gospa": gospa(est, tru, c=gospa_c_m, p=gospa_p),
        "pairs": [{"estimate": i, "truth": j, "error_m": d} for i, j, d in pairs],
    }
