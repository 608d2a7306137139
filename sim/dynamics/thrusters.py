"""Thruster set: first-order rotor lag, dead zone, saturation, asymmetric thrust curve.

Each thruster's normalised rotor speed ``s`` follows its dead-zoned command ``s_cmd``
(:func:`autonomy.control.allocation.command_to_speed`, saturated to [-1, 1]) through a
first-order lag with time constant ``T``, discretised exactly for a step ``dt``::

    s <- s + (1 - exp(-dt / T)) (s_cmd - s)

and thrust is the asymmetric curve of ``s`` (:func:`speed_to_thrust`). The body wrench is
``B @ thrust`` with the layout's (6, n) configuration matrix. Allocation (desired wrench ->
commands) is the pure function shared with the autonomy side.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.control.allocation import (
    ThrusterLayout,
    allocate as _allocate,
    command_to_speed,
    speed_to_thrust,
)
from scenarios.vehicle_params import VehicleParams

FloatArray = NDArray[np.float64]


class ThrusterArray:
    """Rotor states and thrust of a vehicle's thrusters."""

    def __init__(self, params: VehicleParams) -> None:
        self.layout: ThrusterLayout = params.layout
        self.time_constant_s = np.asarray(params.thruster_time_constant_s, dtype=float)
        self.config_matrix = self.layout.config_matrix()
        self.n = self.layout.n
        self._dz = [float(x) for x in self.layout.dead_zone]
        self._fwd = [float(x) for x in self.layout.max_fwd_n]
        self._rev = [float(x) for x in self.layout.max_rev_n]
        self._exp = [float(x) for x in self.layout.curve_exponent]
        self._T = [float(x) for x in self.time_constant_s]
        # Non-zero entries of each column of B: (row, value) pairs.
        self._Bcols = [tuple((i, float(x)) for i, x in enumerate(self.config_matrix[:, j]) if x != 0.0)
                       for j in range(self.n)]
        self._per_thruster = tuple(zip(self._dz, self._fwd, self._rev, self._exp, self._Bcols))
        self._alpha_dt = -1.0
        self._alpha = [1.0] * self.n
        self._cmd_held: list[float] | None = None  # command of the cached speed targets
        self._targets: list[float] = [0.0] * self.n
        self.speed = [0.0] * self.n
        self.thrust_n = [0.0] * self.n

    def reset(self) -> None:
        """Rotors at rest."""
        self.speed = [0.0] * self.n
        self.thrust_n = [0.0] * self.n

    def _alphas(self, dt_s: float) -> list[float]:
        if dt_s != self._alpha_dt:
            self._alpha = [1.0 if T <= 0.0 else 1.0 - math.exp(-dt_s / T) for T in self._T]
            self._alpha_dt = dt_s
        return self._alpha

    def _speed_targets(self, cmd: list[float]) -> list[float]:
        """Normalised rotor speeds (n,) the commands ``cmd`` drive towards (clipped to [-1, 1],
        dead zone removed); ValueError on a NaN command."""
        targets = []
        for j, (dz, *_) in enumerate(self._per_thruster):
            c = float(cmd[j])
            if c != c:
                raise ValueError(f"thruster '{self.layout.names[j]}' command is NaN")
            c = 1.0 if c > 1.0 else (-1.0 if c < -1.0 else c)
            mag = abs(c) - dz
            targets.append(0.0 if mag <= 0.0 else math.copysign(mag / (1.0 - dz), c))
        return targets

    def step(self, cmd: ArrayLike, dt_s: float) -> list[float]:
        """Advance rotors by ``dt_s`` under commands ``cmd`` (n,) in [-1, 1]; return the
        body wrench (6 floats, about CO, FRD) of the new thrusts."""
        if len(cmd) != self.n:
            raise ValueError(f"thruster command needs {self.n} values {self.layout.names}, got {len(cmd)}")
        alpha = self._alphas(dt_s)
        tau = [0.0] * 6
        speed = self.speed
        thrust = self.thrust_n
        cmd = cmd.tolist() if isinstance(cmd, np.ndarray) else list(cmd)  # Python floats: faster scalar arithmetic
        if cmd != self._cmd_held:  # a new command (held over the physics steps of an autonomy period)
            self._targets = self._speed_targets(cmd)
            self._cmd_held = cmd  # never holds a NaN (raised above), so a NaN command is always new
        for j, (target, (_, fwd, rev, ex, bcol)) in enumerate(zip(self._targets, self._per_thruster)):
            s0 = speed[j]
            s = s0 + alpha[j] * (target - s0)
            speed[j] = s
            if s == 0.0:
                f = 0.0
            elif s > 0.0:
                f = fwd * s ** ex
            else:
                f = -rev * (-s) ** ex
            thrust[j] = f
            if f:
                for i, b in bcol:
                    tau[i] += b * f
        return tau

    def steady_thrust(self, cmd: ArrayLike) -> FloatArray:
        """Thrust (n,) the rotors settle at under constant ``cmd`` (vectorised reference)."""
        return speed_to_thrust(command_to_speed(cmd, self.layout.dead_zone), self.layout)

    def allocate(self, wrench_body: ArrayLike, dof_weights: ArrayLike | None = None) -> FloatArray:
        """Commands (n,) in [-1, 1] producing ``wrench_body`` (6,) as well as the layout can."""
        return _allocate(wrench_body, self.layout, dof_weights)
