"""Surge/sway speed model of the vehicle from its commanded force (DVL-free dead reckoning).

Per horizontal body axis ``m dv/dt = F - d_lin v - d_quad v |v|`` ([Fossen2021]: decoupled
surge and sway without Coriolis terms; [vonBenzon2022] for the BlueROV2 Heavy's coefficients),
integrated with the semi-implicit step ``v' = (m v + F dt) / (m + (d_lin + d_quad |v|) dt)``
(stable for any step, exact at the steady state ``F = d_lin v + d_quad v |v|``). What the
model leaves out (thruster dynamics, dead zone and saturation, coupling in turns, currents)
is the velocity error the navigation filter carries as a random walk.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.navigation.config import SpeedModelConfig

FloatArray = NDArray[np.float64]


def steady_speed_mps(force_n: float, d_lin: float, d_quad: float) -> float:
    """Speed (m/s, the sign of the force) at which damping balances ``force_n``:
    the root of ``d_quad v^2 + d_lin v = |F|``."""
    f = abs(force_n)
    v = f / d_lin if d_quad == 0.0 else (-d_lin + np.sqrt(d_lin * d_lin + 4.0 * d_quad * f)) / (2.0 * d_quad)
    return float(np.copysign(v, force_n))


class SpeedModel:
    """Body surge/sway velocity (m/s) from the commanded body force (N).

    Args:
        cfg: mass and damping per axis.
    """

    def __init__(self, cfg: SpeedModelConfig) -> None:
        self.m = np.asarray(cfg.mass_kg, dtype=float)
        self.d_lin = np.asarray(cfg.damping_linear, dtype=float)
        self.d_quad = np.asarray(cfg.damping_quadratic, dtype=float)
        self.vel_mps = np.zeros(2)
        self.force_n = np.zeros(2)

    def set_force(self, force_xy_n: ArrayLike) -> None:
        """Hold the commanded surge, sway force (2,) N until the next command."""
        self.force_n = np.asarray(force_xy_n, dtype=float).reshape(2).copy()

    def step(self, dt_s: float) -> FloatArray:
        """Advance ``dt_s`` s (semi-implicit, module docstring); returns the velocity (2,) m/s."""
        if dt_s > 0.0:
            v = self.vel_mps
            self.vel_mps = (self.m * v + self.force_n * dt_s) / (self.m + (self.d_lin + self.d_quad * np.abs(v)) * dt_s)
        return self.vel_mps.copy()
