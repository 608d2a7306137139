"""Single-measurement initiator (the initiator role): a new Gaussian state from one measurement.

The mean is the model's inverse of the measurement and the covariance its noise carried
through the inverse's Jacobian, ``J R J^T``. Components the measurement does not observe
(e.g. velocity behind a position fix) take the prior's mean and covariance.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.estimation.measurement import PositionFix, RangeBearingElevation

FloatArray = NDArray[np.float64]


class SingleMeasurementInitiator:
    """Starts a state from one measurement.

    Args:
        model: a :class:`PositionFix` (linear) or a model with ``inverse`` and
            ``inverse_jacobian`` whose inverse gives the full state.
        prior_mean: (n,) mean of the unobserved components (default zeros).
        prior_covar: (n, n) covariance of the unobserved components (default zeros).
    """

    def __init__(self, model: PositionFix | RangeBearingElevation, prior_mean: ArrayLike | None = None,
                 prior_covar: ArrayLike | None = None) -> None:
        self.model = model
        self.prior_mean = None if prior_mean is None else np.asarray(prior_mean, dtype=float)
        self.prior_covar = None if prior_covar is None else np.asarray(prior_covar, dtype=float)

    def initiate(self, z: ArrayLike, noise_covar: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Mean (n,) and covariance (n, n) of the state that produced ``z`` with noise R."""
        R = np.asarray(noise_covar, dtype=float)
        model = self.model
        if isinstance(model, PositionFix):
            idx = model.mapping
            mean = np.zeros(model.ndim_state) if self.prior_mean is None else self.prior_mean.copy()
            covar = (np.zeros((model.ndim_state,) * 2) if self.prior_covar is None
                     else self.prior_covar.copy())
            mean[idx] = np.asarray(z, dtype=float)
            covar[:, idx] = 0.0
            covar[idx, :] = 0.0
            covar[np.ix_(idx, idx)] = R
            return mean, covar
        J = model.inverse_jacobian(z)
        return model.inverse(z), J @ R @ J.T
