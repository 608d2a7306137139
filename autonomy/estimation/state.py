"""The Gaussian state the estimation roles pass between them: a mean, its covariance and the
time they hold at (Stone Soup's ``GaussianState``, [StoneSoup])."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class GaussianState:
    """A Gaussian estimate.

    Attributes:
        mean: (n,) the state's mean (units and frame: the estimator's state, e.g. NED m).
        covar: (n, n) its covariance, symmetric.
        t_s: the time the estimate holds at, s (``nan``: undated).

    Both arrays are held as read-only views of the ones given (no copy, so the caller must not
    change those afterwards; :meth:`of` copies): a role makes a new state, it never changes
    one in place (a stored state, e.g. a re-processing checkpoint, stays what it was).

    Raises:
        ValueError: a mean that is not one-dimensional or a covariance that is not (n, n).
    """

    mean: FloatArray
    covar: FloatArray
    t_s: float = math.nan

    def __post_init__(self) -> None:
        mean = np.asarray(self.mean, dtype=float)
        covar = np.asarray(self.covar, dtype=float)
        if mean.ndim != 1 or covar.shape != (mean.size, mean.size):
            raise ValueError(f"GaussianState: mean must be (n,) and covar (n, n), got {mean.shape} and {covar.shape}")
        mean, covar = mean.view(), covar.view()
        mean.flags.writeable = covar.flags.writeable = False
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "covar", covar)
        object.__setattr__(self, "t_s", float(self.t_s))

    @property
    def ndim(self) -> int:
        """The state's dimension n."""
        return int(self.mean.size)

    @classmethod
    def of(cls, mean: ArrayLike, covar: ArrayLike, t_s: float = math.nan) -> GaussianState:
        """A state from array-likes (copied)."""
        return cls(np.array(mean, dtype=float), np.array(covar, dtype=float), t_s)
