"""Surge-speed, sway, heading and depth/altitude autopilots producing a body wrench.

The output is the desired generalised force ``[X, Y, Z, K, M, N]`` in the body (FRD) frame
(N and N m) with ``K = M = 0``: roll and pitch are left to the hull's metacentric
stability. The thrust allocation maps it to thruster commands.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from autonomy.control.config import ControlConfig
from autonomy.control.pid import Pid
from autonomy.control.setpoint import Setpoint
from autonomy.messages import NavEstimate

FloatArray = NDArray[np.float64]


def _wrap(angle_rad: float) -> float:
    """Wrap to [-pi, pi)."""
    return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi


def _slew(current: float, target: float, max_step: float) -> float:
    return current + min(max(target - current, -max_step), max_step)


class Autopilot:
    """Four decoupled loops: surge speed, sway speed, heading, depth (or altitude).

    Setpoints are first shaped by slew-rate limits (speed, heading, depth references
    start from the measured state on the first update after :meth:`reset`, so engaging is
    bumpless), then tracked by PIDs whose derivative acts on the measured rate minus the
    (smooth, slew-limited) reference rate, so setpoint steps cause no derivative kick.

    Altitude mode tracks the depth ``seabed_depth - altitude_sp``, with the seabed depth
    estimated as ``depth + measured altitude`` and low-pass filtered; while the altitude is
    invalid (NaN) the last seabed estimate is kept (or the current depth held if none).
    """

    def __init__(self, cfg: ControlConfig) -> None:
        self.cfg = cfg
        self._max_yaw_rate_radps = math.radians(cfg.max_yaw_rate_dps)
        self.surge_pid = Pid(cfg.surge)
        self.sway_pid = Pid(cfg.sway)
        self.heading_pid = Pid(cfg.heading)
        self.depth_pid = Pid(cfg.depth)
        self.reset()

    def reset(self) -> None:
        for pid in (self.surge_pid, self.sway_pid, self.heading_pid, self.depth_pid):
            pid.reset()
        self.speed_ref_mps: float | None = None
        self.heading_ref_rad: float | None = None
        self.depth_ref_m: float | None = None
        self.seabed_depth_m: float | None = None
        self.depth_target_m: float = math.nan

    def _update_seabed(self, depth_m: float, altitude_m: float, dt_s: float) -> None:
        if not math.isfinite(altitude_m):
            return
        sample = depth_m + altitude_m
        if self.seabed_depth_m is None or self.cfg.altitude_filter_tau_s <= 0.0:
            self.seabed_depth_m = sample
        else:
            alpha = dt_s / (self.cfg.altitude_filter_tau_s + dt_s)
            self.seabed_depth_m += alpha * (sample - self.seabed_depth_m)

    def update(self, nav: NavEstimate, setpoint: Setpoint, dt_s: float) -> FloatArray:
        """One control step.

        Args:
            nav: navigation estimate (pos_ned, rpy_rad, vel_body_mps, rate_body_radps,
                altitude_m).
            setpoint: desired speed, heading and depth or altitude.
            dt_s: time since the previous call, s (> 0).

        Returns:
            Desired body wrench ``[X, Y, Z, 0, 0, N]``, shape (6,), N and N m.
        """
        if not dt_s > 0.0:
            raise ValueError(f"dt_s must be > 0, got {dt_s}")
        p = self.cfg
        roll, pitch, yaw = (float(a) for a in nav.rpy_rad)
        u, v, w = (float(x) for x in nav.vel_body_mps)
        _, q, r = (float(x) for x in nav.rate_body_radps)
        depth = float(nav.pos_ned[2])
        if not math.isfinite(roll + pitch + yaw + u + v + w + q + r + depth):
            raise ValueError(
                "Autopilot.update: NavEstimate pos_ned[2], rpy_rad, vel_body_mps and "
                "rate_body_radps must be finite (pass no nav to the mission FSM instead)"
            )
        sr, cr, sp, cp = math.sin(roll), math.cos(roll), math.sin(pitch), math.cos(pitch)
        depth_rate = -sp * u + cp * sr * v + cp * cr * w  # third row of R_nb @ v_body
        yaw_rate = (sr * q + cr * r) / cp  # third row of T(Theta) @ [p, q, r] (Fossen 2.41)

        # Reference shaping (bumpless start from the measured state).
        if self.speed_ref_mps is None:
            self.speed_ref_mps = u
            self.heading_ref_rad = yaw
            self.depth_ref_m = depth
        self.speed_ref_mps = _slew(self.speed_ref_mps, setpoint.speed_mps, p.max_acceleration_mps2 * dt_s)
        heading_step = _slew(0.0, _wrap(setpoint.heading_rad - self.heading_ref_rad),
                             self._max_yaw_rate_radps * dt_s)
        self.heading_ref_rad = _wrap(self.heading_ref_rad + heading_step)

        self._update_seabed(depth, float(nav.altitude_m), dt_s)
        if setpoint.depth_m is not None:
            target = setpoint.depth_m
        elif self.seabed_depth_m is not None:
            target = max(self.seabed_depth_m - setpoint.altitude_m, 0.0)
        else:
            target = self.depth_ref_m
        self.depth_target_m = target
        depth_step = _slew(0.0, target - self.depth_ref_m, p.max_vertical_speed_mps * dt_s)
        self.depth_ref_m += depth_step

        x = self.surge_pid.update(
            self.speed_ref_mps - u, u, dt_s, measurement_rate=0.0,
            feedforward=p.surge_feedforward_n_per_mps * self.speed_ref_mps,
        )
        y = self.sway_pid.update(setpoint.sway_mps - v, v, dt_s, measurement_rate=0.0)
        n = self.heading_pid.update(
            _wrap(self.heading_ref_rad - yaw), yaw, dt_s,
            measurement_rate=yaw_rate - heading_step / dt_s,
        )
        z = self.depth_pid.update(
            self.depth_ref_m - depth, depth, dt_s, measurement_rate=depth_rate - depth_step / dt_s,
            feedforward=p.heave_bias_n,
        )
        return np.array([x, y, z, 0.0, 0.0, n])
