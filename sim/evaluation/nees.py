"""Filter consistency: normalised estimation error squared (NEES) and its chi-square band.

A consistent estimator's NEES ``e^T P^-1 e`` of a d-dimensional error is chi-square with d
degrees of freedom; the mean of n independent ones lies, with 95 % probability, in
``[chi2.ppf(0.025, n d) / n, chi2.ppf(0.975, n d) / n]`` (Bar-Shalom, Li and Kirubarajan
2001, section 5.4, [BarShalom2001] in docs/references.md).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2

FloatArray = NDArray[np.float64]


def horizontal_nees(err_ne_m: FloatArray, covar_ne_m2: FloatArray) -> float:
    """Normalised estimation error squared ``e^T P^-1 e`` of a horizontal error (2,) m with
    its covariance (2, 2) m^2 (chi-square with 2 degrees of freedom for a consistent filter);
    NaN for a singular covariance."""
    try:
        return float(err_ne_m @ np.linalg.solve(covar_ne_m2, err_ne_m))
    except np.linalg.LinAlgError:
        return math.nan


def mean_nees_band(n: int, dof: int, probability: float = 0.95) -> tuple[float, float]:
    """Two-sided ``probability`` interval of the mean of ``n`` independent chi-square(``dof``)
    NEES values ((nan, nan) for n = 0)."""
    if n <= 0:
        return math.nan, math.nan
    tail = 0.5 * (1.0 - probability)
    return float(chi2.ppf(tail, n * dof) / n), float(chi2.ppf(1.0 - tail, n * dof) / n)


def nees_summary(values: list[float] | FloatArray, dof: int) -> dict:
    """``n``, ``mean``, ``band_95`` (:func:`mean_nees_band`), ``within_band``, ``above_95_fraction``
    (share above the chi-square 95 % point; 0.05 when consistent) of finite NEES ``values``."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    lo, hi = mean_nees_band(int(v.size), dof)
    mean = float(v.mean()) if v.size else math.nan
    return {"n": int(v.size), "mean": mean, "dof": dof, "band_95": [lo, hi],
            "within_band": bool(v.size and lo <= mean <= hi),
            "above_95_fraction": float(np.mean(v > chi2.ppf(0.95, dof))) if v.size else math.nan}
