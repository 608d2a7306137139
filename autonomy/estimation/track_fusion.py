"""Track-to-track association and fusion: two tracks that are one object.

A multiple-hypothesis tracker can end up holding two tracks of one object in its best
hypothesis (track coalescence: a second track is born when one look falls outside the
first's gate, and from then on each absorbs some of the object's detections). The
standard remedy is a track-to-track test and fusion [BarShalomCampo1986], [BarShalom2001]:
under the hypothesis that tracks 1 and 2 estimate the same state, their difference
``d = x1 - x2`` is zero-mean with covariance

    S = P1 + P2 - P12 - P12^T,

where ``P12`` is the cross-covariance of their errors. Tracks built from disjoint detections
share only the errors the detections share (the platform's navigation error, where on the
object the boxes land): with ``P_i`` containing ``C_i C_i^T`` for the sensitivities ``C_i``
(d, q) of track i's error to those q common parameters, ``P12 = C1 C2^T``. The tracks are one
object when ``d^T S^-1 d <= gate`` (chi-square, ``d`` dof), and the fused estimate is
Bar-Shalom and Campo's

    x = x1 + (P1 - P12) S^-1 (x2 - x1),    P = P1 - (P1 - P12) S^-1 (P1 - P12)^T.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def cross_covariance(consider_1: ArrayLike | None, consider_2: ArrayLike | None, dim: int) -> FloatArray:
    """``P12 = C1 C2^T`` (dim, dim) of two tracks' errors from their common-parameter
    sensitivities (dim, q); zeros when either is None (no common error)."""
    if consider_1 is None or consider_2 is None:
        return np.zeros((dim, dim))
    return np.asarray(consider_1, dtype=float) @ np.asarray(consider_2, dtype=float).T


def track_distance2(x1: ArrayLike, P1: ArrayLike, x2: ArrayLike, P2: ArrayLike,
                    P12: ArrayLike | None = None) -> float:
    """Squared Mahalanobis distance ``d^T S^-1 d`` of two track estimates (d,) with
    covariances (d, d) and cross-covariance ``P12`` (d, d) (default zero), under the
    hypothesis that they estimate one state. ``inf`` where ``S`` is singular."""
    x1, x2 = np.asarray(x1, dtype=float), np.asarray(x2, dtype=float)
    P12 = np.zeros((len(x1), len(x1))) if P12 is None else np.asarray(P12, dtype=float)
    S = np.asarray(P1, dtype=float) + np.asarray(P2, dtype=float) - P12 - P12.T
    d = x1 - x2
    try:
        return float(d @ np.linalg.solve(S, d))
    except np.linalg.LinAlgError:
        return float("inf")


def fuse_tracks(x1: ArrayLike, P1: ArrayLike, x2: ArrayLike, P2: ArrayLike,
                P12: ArrayLike | None = None) -> tuple[FloatArray, FloatArray]:
    """Bar-Shalom-Campo fusion of two estimates of one state [BarShalomCampo1986].

    Args:
        x1, x2: (d,) estimates.
        P1, P2: (d, d) their covariances.
        P12: (d, d) cross-covariance ``E[e1 e2^T]`` (default zero: independent errors, when
            the fusion is the information-weighted mean).

    Returns:
        The fused estimate (d,) and covariance (d, d), symmetrised.

    Raises:
        numpy.linalg.LinAlgError: ``P1 + P2 - P12 - P12^T`` is singular.
    """
    x1, x2 = np.asarray(x1, dtype=float), np.asarray(x2, dtype=float)
    P1, P2 = np.asarray(P1, dtype=float), np.asarray(P2, dtype=float)
    P12 = np.zeros_like(P1) if P12 is None else np.asarray(P12, dtype=float)
    S = P1 + P2 - P12 - P12.T
    K = np.linalg.solve(S.T, (P1 - P12).T).T  # (P1 - P12) S^-1
    x = x1 + K @ (x2 - x1)
    P = P1 - K @ (P1 - P12).T
    return x, 0.5 * (P + P.T)
