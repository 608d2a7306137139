"""Ocean current: constant plus a first-order Gauss-Markov part (pure numpy).

The horizontal (north, east) Gauss-Markov component ``b`` obeys
``db = -b / tau dt + sigma sqrt(2 / tau) dW`` and is advanced with its exact
discretisation ``b <- exp(-dt/tau) b + sigma sqrt(1 - exp(-2 dt/tau)) n``, ``n ~ N(0, I2)``,
so its stationary standard deviation is ``sigma`` whatever the step. It starts from zero
(a calm start) and draws only from the generator it is given.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from scenarios.config.world import CurrentConfig

FloatArray = NDArray[np.float64]


class OceanCurrent:
    """Water velocity in NED (m/s), uniform in space."""

    def __init__(self, cfg: CurrentConfig, rng: np.random.Generator | None) -> None:
        self.cfg = cfg
        self.mean_ned = np.asarray(cfg.velocity_ned_mps, dtype=float)
        self.sigma_mps = float(cfg.gauss_markov_sigma_mps)
        self.tau_s = float(cfg.gauss_markov_tau_s)
        if self.sigma_mps > 0.0 and rng is None:
            raise ValueError("OceanCurrent with gauss_markov_sigma_mps > 0 needs a seeded rng")
        self._rng = rng
        self._gm_ne = np.zeros(2)
        self._coef_dt = -1.0
        self._phi = 1.0
        self._q = 0.0
        self._value = tuple(float(x) for x in self.mean_ned)
        #: True when the water never moves (lets the physics skip the current terms).
        self.is_still: bool = self.sigma_mps == 0.0 and not np.any(self.mean_ned)

    @property
    def velocity_ned(self) -> FloatArray:
        return np.array(self._value)

    @property
    def velocity_tuple(self) -> tuple[float, float, float]:
        return self._value

    def reset(self) -> None:
        self._gm_ne = np.zeros(2)
        self._value = tuple(float(x) for x in self.mean_ned)

    def step(self, dt_s: float) -> tuple[float, float, float]:
        """Advance by ``dt_s`` and return the current (north, east, down) in m/s."""
        if self.sigma_mps == 0.0:
            return self._value
        if dt_s != self._coef_dt:
            self._phi = math.exp(-dt_s / self.tau_s)
            self._q = self.sigma_mps * math.sqrt(1.0 - self._phi * self._phi)
            self._coef_dt = dt_s
        self._gm_ne = self._phi * self._gm_ne + self._q * self._rng.standard_normal(2)
        n, e = self._gm_ne
        self._value = (self.mean_ned[0] + n, self.mean_ned[1] + e, float(self.mean_ned[2]))
        return self._value
