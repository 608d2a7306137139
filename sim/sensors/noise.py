"""Seeded sensor noise processes: white noise, random-walk biases, dropouts.

Every process draws from a generator passed in (``sim.rng.component_rng``), so a sensor's
noise depends only on the root seed and the sensor's name.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def white_noise(rng: np.random.Generator, sigma: ArrayLike, size: int | tuple[int, ...] | None = None) -> FloatArray:
    """Zero-mean Gaussian samples with standard deviation ``sigma`` (broadcast to ``size``)."""
    sigma = np.asarray(sigma, dtype=float)
    if size is None:
        size = sigma.shape
    return rng.standard_normal(size) * sigma


def dropped(rng: np.random.Generator, prob: float) -> bool:
    """True with probability ``prob`` (no draw when ``prob`` is 0)."""
    return prob > 0.0 and bool(rng.random() < prob)


class RandomWalkBias:
    """Bias ``b(t) = b0 + integral of white noise``: ``b0 ~ N(0, initial_sigma^2)`` drawn once,
    then ``b(t + dt) - b(t) ~ N(0, rw_sigma^2 dt)``.

    The process advances to the ``t_s`` it is queried at, so it keeps the time of the last query,
    not a clock of its own. Shapes follow ``initial_sigma``.

    Args:
        rng: noise generator.
        initial_sigma: per-component sigma of the constant part (units of the bias).
        rw_sigma_per_sqrt_s: per-component random-walk density (units / sqrt(s)).
    """

    def __init__(self, rng: np.random.Generator, initial_sigma: ArrayLike, rw_sigma_per_sqrt_s: ArrayLike = 0.0):
        self._rng = rng
        sigma0 = np.asarray(initial_sigma, dtype=float)
        self._rw = np.broadcast_to(np.asarray(rw_sigma_per_sqrt_s, dtype=float), sigma0.shape).copy()
        if np.any(sigma0 < 0.0) or np.any(self._rw < 0.0):
            raise ValueError("RandomWalkBias: sigmas must be non-negative")
        self._value = white_noise(rng, sigma0)
        self._walks = bool(np.any(self._rw > 0.0))
        self._t_s: float | None = None

    def at(self, t_s: float) -> FloatArray:
        """Bias at time ``t_s`` (s); times must not go backwards."""
        if self._t_s is not None:
            dt = t_s - self._t_s
            if dt < 0.0:
                raise ValueError(f"RandomWalkBias queried at t={t_s} s before previous t={self._t_s} s")
            if dt > 0.0 and self._walks:
                self._value = self._value + white_noise(self._rng, self._rw * math.sqrt(dt))
        self._t_s = float(t_s)
        return self._value.copy()
