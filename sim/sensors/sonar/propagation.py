"""Two-way propagation losses and their compensation by time-varied gain (pure numpy).

Sonar equation terms in power (Urick, *Principles of Underwater Sound*; see
``docs/references.md``): a point target at slant range ``r`` returns ``r^-4 10^(-2 alpha r / 10)``
of the transmitted intensity (spherical spreading and absorption ``alpha`` dB/m, both ways).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def transmission_gain(range_m: ArrayLike, absorption_db_per_m: float) -> FloatArray:
    """Two-way power factor of ray-sampled returns: ``r^-2 10^(-2 alpha r / 10)``.

    Rays sample solid angle, so an area patch hit by one ray grows as ``r^2`` and the two-way
    spherical spreading ``r^-4`` leaves ``r^-2`` per ray (a point target, hit by ~``1/r^2`` rays,
    keeps its ``r^-4``).

    Args:
        range_m: (...) slant range (m), clipped below at 1 mm.
        absorption_db_per_m: one-way absorption coefficient ``alpha``.

    Returns:
        (...) power factor.
    """
    r = np.maximum(np.asarray(range_m, dtype=float), 1e-3)
    return r ** -2 * 10.0 ** (-0.2 * absorption_db_per_m * r)


def tvg_gain(range_m: ArrayLike, db_per_decade: float, absorption_db_per_m: float) -> FloatArray:
    """Time-varied gain (power factor) ``N log10 r + 2 alpha r`` dB at slant range ``r`` (m).

    ``db_per_decade = 40`` with the true ``alpha`` undoes a point target's two-way loss
    ``r^-4 10^(-2 alpha r / 10)`` exactly.
    """
    r = np.maximum(np.asarray(range_m, dtype=float), 1e-3)
    return 10.0 ** (0.1 * (db_per_decade * np.log10(r) + 2.0 * absorption_db_per_m * r))
