"""Thrust allocation and thruster command curves (pure numpy, shared by sim and autonomy).

A thruster ``i`` at ``pos_body_m[i]`` (FRD, from the body origin) pushing along unit
``dir_body[i]`` with thrust ``f_i`` (N) adds ``f_i * [d_i, r_i x d_i]`` to the body
wrench, so ``tau = B @ f`` with the (6, n) configuration matrix ``B``.

Command curve (per thruster, command ``c`` in [-1, 1]):

* dead zone: ``|c| <= dead_zone`` gives no thrust; above it the command is rescaled
  ``s = sign(c) (|c| - dead_zone) / (1 - dead_zone)`` (normalised rotor speed, in [-1, 1]);
* asymmetric curve: ``f = max_fwd_n * s**p`` for ``s >= 0``, ``-max_rev_n * |s|**p``
  otherwise (``p = curve_exponent``, 2 for thrust ~ rpm^2 propellers).

Allocation solves ``B f = tau`` in the least-squares sense with a weighted generalised
inverse, then handles saturation by *redistribution*: thrusters driven past a limit are
clamped there, removed from the free set, and the residual wrench is re-allocated among
the remaining ones; repeated until nothing saturates (at most ``n`` passes). Wrenches the
layout cannot produce (e.g. roll/pitch for a 4-DOF vehicle) are matched in least squares.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class ThrusterLayout:
    """Geometry and limits of a thruster set.

    Attributes:
        names: (n,) thruster names.
        pos_body_m: (n, 3) thruster positions in FRD from the body origin, m.
        dir_body: (n, 3) unit thrust directions (positive command) in FRD.
        max_fwd_n: (n,) thrust at command +1, N (> 0).
        max_rev_n: (n,) thrust magnitude at command -1, N (> 0).
        dead_zone: (n,) command magnitude below which no thrust is produced, [0, 1).
        curve_exponent: (n,) exponent p of the thrust-vs-normalised-speed curve.
    """

    names: tuple[str, ...]
    pos_body_m: FloatArray
    dir_body: FloatArray
    max_fwd_n: FloatArray
    max_rev_n: FloatArray
    dead_zone: FloatArray
    curve_exponent: FloatArray

    def __post_init__(self) -> None:
        n = len(self.names)
        for key in ("pos_body_m", "dir_body"):
            arr = np.asarray(getattr(self, key), dtype=float)
            if arr.shape != (n, 3):
                raise ValueError(f"ThrusterLayout.{key} must have shape ({n}, 3), got {arr.shape}")
            object.__setattr__(self, key, arr)
        for key in ("max_fwd_n", "max_rev_n", "dead_zone", "curve_exponent"):
            arr = np.broadcast_to(np.asarray(getattr(self, key), dtype=float), (n,)).copy()
            object.__setattr__(self, key, arr)
        norms = np.linalg.norm(self.dir_body, axis=1)
        if np.any(norms < 1e-9):
            raise ValueError("ThrusterLayout.dir_body rows must be non-zero")
        object.__setattr__(self, "dir_body", self.dir_body / norms[:, None])
        if np.any(self.max_fwd_n <= 0) or np.any(self.max_rev_n <= 0):
            raise ValueError("ThrusterLayout.max_fwd_n and max_rev_n must be > 0")
        if np.any(self.dead_zone < 0) or np.any(self.dead_zone >= 1):
            raise ValueError("ThrusterLayout.dead_zone must be in [0, 1)")
        if np.any(self.curve_exponent <= 0):
            raise ValueError("ThrusterLayout.curve_exponent must be > 0")
        for arr in (self.pos_body_m, self.dir_body, self.max_fwd_n, self.max_rev_n,
                    self.dead_zone, self.curve_exponent):
            arr.setflags(write=False)

    @property
    def n(self) -> int:
        return len(self.names)

    def config_matrix(self) -> FloatArray:
        """(6, n) matrix B with ``tau_body = B @ thrust_n``."""
        moments = np.cross(self.pos_body_m, self.dir_body)
        return np.vstack([self.dir_body.T, moments.T])


def command_to_speed(cmd: ArrayLike, dead_zone: ArrayLike) -> FloatArray:
    """Normalised rotor speed in [-1, 1] for commands in [-1, 1] (dead zone applied)."""
    c = np.clip(np.asarray(cmd, dtype=float), -1.0, 1.0)
    dz = np.asarray(dead_zone, dtype=float)
    mag = np.maximum(np.abs(c) - dz, 0.0) / (1.0 - dz)
    return np.sign(c) * mag


def speed_to_thrust(speed: ArrayLike, layout: ThrusterLayout) -> FloatArray:
    """Thrust (N) of normalised rotor speeds ``speed`` (n,), asymmetric curve."""
    s = np.asarray(speed, dtype=float)
    mag = np.abs(s) ** layout.curve_exponent
    return np.where(s >= 0.0, layout.max_fwd_n * mag, -layout.max_rev_n * mag)


def command_to_thrust(cmd: ArrayLike, layout: ThrusterLayout) -> FloatArray:
    """Steady-state thrust (N) of commands ``cmd`` (n,) in [-1, 1]."""
    return speed_to_thrust(command_to_speed(cmd, layout.dead_zone), layout)


def thrust_to_command(thrust_n: ArrayLike, layout: ThrusterLayout) -> FloatArray:
    """Command in [-1, 1] whose steady thrust is ``thrust_n`` (clipped to the limits).

    Inverse of :func:`command_to_thrust`: a non-zero thrust maps to a command just past
    the dead zone, zero thrust to zero command.
    """
    f = np.asarray(thrust_n, dtype=float)
    frac = np.where(f >= 0.0, f / layout.max_fwd_n, -f / layout.max_rev_n)
    frac = np.clip(frac, 0.0, 1.0)
    speed = frac ** (1.0 / layout.curve_exponent)
    cmd = np.where(speed > 0.0, layout.dead_zone + (1.0 - layout.dead_zone) * speed, 0.0)
    return np.sign(f) * cmd


def allocate_thrust(
    wrench_body: ArrayLike,
    config_matrix: ArrayLike,
    thrust_min_n: ArrayLike,
    thrust_max_n: ArrayLike,
    dof_weights: ArrayLike | None = None,
    pinv_cache: dict[bytes, FloatArray] | None = None,
) -> FloatArray:
    """Thrusts (n,) best producing ``wrench_body`` (6,) within ``[thrust_min, thrust_max]``.

    Weighted least squares ``min || W^(1/2) (B f - tau) ||`` (minimum-norm ``f`` among
    solutions) with redistribution of saturated thrusters; see the module docstring.
    ``dof_weights`` (6,) weighs the wrench components (default all ones).
    ``pinv_cache`` (owned by the caller, valid for one matrix and weights) memoises the
    pseudo-inverse of each set of unsaturated thrusters.
    """
    tau = np.asarray(wrench_body, dtype=float).reshape(6)
    B, lo, hi, w_sqrt = _checked_problem(config_matrix, thrust_min_n, thrust_max_n, dof_weights)
    return _allocate_weighted(w_sqrt * tau, w_sqrt[:, None] * B, lo, hi, pinv_cache)


def _checked_problem(config_matrix: ArrayLike, thrust_min_n: ArrayLike, thrust_max_n: ArrayLike,
                     dof_weights: ArrayLike | None) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """``(B (6, n), thrust_min (n,), thrust_max (n,), sqrt(dof_weights) (6,))`` as float arrays;
    ValueError on wrong shapes or limits that do not bracket zero thrust."""
    B = np.asarray(config_matrix, dtype=float)
    lo = np.asarray(thrust_min_n, dtype=float)
    hi = np.asarray(thrust_max_n, dtype=float)
    n = B.shape[1]
    if B.shape != (6, n) or lo.shape != (n,) or hi.shape != (n,):
        raise ValueError("allocate_thrust: config_matrix must be (6, n), limits (n,)")
    if np.any(lo > 0.0) or np.any(hi < 0.0):
        raise ValueError("allocate_thrust: limits must bracket zero thrust")
    w_sqrt = np.ones(6) if dof_weights is None else np.sqrt(np.asarray(dof_weights, dtype=float))
    return B, lo, hi, w_sqrt


def _allocate_weighted(tw: FloatArray, Bw: FloatArray, lo: FloatArray, hi: FloatArray,
                       pinv_cache: dict[bytes, FloatArray] | None) -> FloatArray:
    """:func:`allocate_thrust` on the weighted problem ``tw = W^(1/2) tau`` (6,),
    ``Bw = W^(1/2) B`` (6, n), limits checked."""
    n = Bw.shape[1]
    thrust = np.zeros(n)
    free = np.ones(n, dtype=bool)
    for _ in range(n):
        residual = tw - Bw @ thrust
        key = free.tobytes()
        pinv = None if pinv_cache is None else pinv_cache.get(key)
        if pinv is None:
            pinv = np.linalg.pinv(Bw[:, free], rcond=1e-9)
            if pinv_cache is not None:
                pinv_cache[key] = pinv
        sol = pinv @ residual
        trial = thrust.copy()
        trial[free] += sol
        over = free & ((trial > hi + 1e-12) | (trial < lo - 1e-12))
        if not np.any(over):
            return trial
        # Scale the free update uniformly to the first limit hit, clamp that thruster
        # and re-allocate what is left among the others.
        idx = np.flatnonzero(free)
        with np.errstate(divide="ignore", invalid="ignore"):
            up = np.where(sol > 0, (hi[idx] - thrust[idx]) / sol, np.inf)
            down = np.where(sol < 0, (lo[idx] - thrust[idx]) / sol, np.inf)
        ratio = np.minimum(up, down)
        k = int(np.argmin(ratio))
        step = float(np.clip(ratio[k], 0.0, 1.0))
        thrust[idx] += step * sol
        j = idx[k]
        thrust[j] = hi[j] if sol[k] > 0 else lo[j]
        free[j] = False
        if not np.any(free):
            break
    return np.clip(thrust, lo, hi)


def allocate(wrench_body: ArrayLike, layout: ThrusterLayout,
             dof_weights: ArrayLike | None = None) -> FloatArray:
    """Thruster commands (n,) in [-1, 1] producing ``wrench_body`` (6,) as well as possible."""
    thrust = allocate_thrust(wrench_body, layout.config_matrix(), -layout.max_rev_n,
                             layout.max_fwd_n, dof_weights)
    return thrust_to_command(thrust, layout)


class ThrustAllocator:
    """Allocation bound to one thruster set (what the onboard controller holds).

    Args:
        config_matrix: (6, n) matrix B, ``tau = B @ thrust``.
        thrust_limits_n: (n, 2) rows ``[min, max]`` thrust in N (min <= 0 <= max).
        layout: the thrusters' command curves, needed by :meth:`allocate` to turn thrust
            into commands (use :meth:`from_layout` to take everything from it).
        dof_weights: optional (6,) weights of the wrench components.
    """

    def __init__(self, config_matrix: ArrayLike, thrust_limits_n: ArrayLike,
                 layout: ThrusterLayout | None = None, dof_weights: ArrayLike | None = None) -> None:
        self.config_matrix = np.asarray(config_matrix, dtype=float)
        limits = np.asarray(thrust_limits_n, dtype=float)
        n = self.config_matrix.shape[1]
        if self.config_matrix.shape != (6, n) or limits.shape != (n, 2):
            raise ValueError(f"ThrustAllocator: config_matrix must be (6, n) and thrust_limits_n "
                             f"(n, 2), got {self.config_matrix.shape} and {limits.shape}")
        self.thrust_min_n, self.thrust_max_n = limits[:, 0].copy(), limits[:, 1].copy()
        self.layout = layout
        self.dof_weights = dof_weights
        self._pinv_cache: dict[bytes, FloatArray] = {}
        # the weighted problem, checked and formed once (allocation runs at the autonomy rate)
        _, lo, hi, self._w_sqrt = _checked_problem(self.config_matrix, self.thrust_min_n, self.thrust_max_n,
                                                   dof_weights)
        self._Bw = self._w_sqrt[:, None] * self.config_matrix
        self._limits = (lo, hi)

    @classmethod
    def from_layout(cls, layout: ThrusterLayout, dof_weights: ArrayLike | None = None) -> "ThrustAllocator":
        limits = np.column_stack([-layout.max_rev_n, layout.max_fwd_n])
        return cls(layout.config_matrix(), limits, layout, dof_weights)

    def allocate_thrust(self, wrench_body: ArrayLike) -> FloatArray:
        """Thrusts (n,) in N for the desired body wrench (6,)."""
        tau = np.asarray(wrench_body, dtype=float).reshape(6)
        return _allocate_weighted(self._w_sqrt * tau, self._Bw, *self._limits, self._pinv_cache)

    def allocate(self, wrench_body: ArrayLike) -> FloatArray:
        """Thruster commands (n,) in [-1, 1] for the desired body wrench (6,)."""
        if self.layout is None:
            raise ValueError("ThrustAllocator.allocate needs the thrusters' command curves: "
                             "build it with layout=params.layout or ThrustAllocator.from_layout")
        return thrust_to_command(self.allocate_thrust(wrench_body), self.layout)
