"""Kalman predictor (the predictor role): a Gaussian state carried forward by a transition model.

``x- = f(x, dt)``, ``P- = F P F^T + Q`` (Kalman 1960). The transition models here are
linear, so the extended Kalman predictor (F the Jacobian of f) is the same computation.
Optionally, a state left unmeasured for longer than ``fallback_after_s`` falls back to a
fixed-uncertainty Gaussian ``fallback_covar`` around its mean (paper 000 section V-B: the
anchor position "switches to a multidimensional Gaussian with mean the current position
values and covariance previously set matrices").
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.estimation.roles import TransitionModel

FloatArray = NDArray[np.float64]


class KalmanPredictor:
    """Predicts Gaussian states with ``transition``.

    Args:
        transition: the transition model.
        fallback_after_s: time without a measurement after which the covariance is replaced
            by ``fallback_covar`` (None: never).
        fallback_covar: (n, n) covariance of the fallback Gaussian.

    Raises:
        ValueError: only one of the fallback arguments given, or a bad shape.
    """

    def __init__(
        self,
        transition: TransitionModel,
        fallback_after_s: float | None = None,
        fallback_covar: ArrayLike | None = None,
    ) -> None:
        if (fallback_after_s is None) != (fallback_covar is None):
            raise ValueError("KalmanPredictor needs both fallback_after_s and fallback_covar, or neither")
        self.transition = transition
        self.fallback_after_s = None if fallback_after_s is None else float(fallback_after_s)
        n = transition.ndim_state
        self.fallback_covar = None if fallback_covar is None else np.asarray(fallback_covar, dtype=float)
        if self.fallback_covar is not None and self.fallback_covar.shape != (n, n):
            raise ValueError(f"fallback_covar must be ({n}, {n}), got {self.fallback_covar.shape}")

    def predict(self, mean: ArrayLike, covar: ArrayLike, dt_s: float) -> tuple[FloatArray, FloatArray]:
        """Mean (n,) and covariance (n, n) ``dt_s`` >= 0 seconds after the last measurement."""
        return self.transition.function(mean, dt_s), self.predict_covar(covar, dt_s)

    def predict_covar(self, covar: ArrayLike, dt_s: ArrayLike) -> FloatArray:
        """Covariances (..., n, n) after ``dt_s`` (() or (...)) seconds, with the fallback."""
        P = self.transition.propagate_covar(covar, dt_s)
        if self.fallback_after_s is not None:
            stale = np.asarray(dt_s) > self.fallback_after_s
            if P.ndim == 2:
                if stale:
                    P = self.fallback_covar.copy()
            else:
                P[stale] = self.fallback_covar
        return P
