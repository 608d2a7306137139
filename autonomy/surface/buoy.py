"""The moving buoy's autonomy: GNSS station keeping, or following a point (the AUV, from
the buoy's USBL fixes) at a horizontal offset.

:class:`SurfaceAutonomy` is ticked by the mission loop at its rate with the GNSS fixes and
compass reading that arrived since the last tick and, when following, the latest position of
the followed vehicle; it returns normalised thruster commands. Guidance and control are in
:class:`autonomy.surface.config.SurfaceAutonomyConfig`: position loop -> velocity demand
(+ the followed point's velocity), velocity loop with an integral of the position error
+ surge-drag feedforward - estimated disturbance -> NED force, heading along the low-passed steady force, drag feedforward + integral - disturbance
estimate (weathervaning in a hold, as weather-optimal positioning control does,
[FossenStrand2001]), yaw PD (critically damped second order). Source: paper 000 section
VII-B ([P000]) for the buoy's role; the control is ours.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.control.allocation import ThrustAllocator, ThrusterLayout, command_to_thrust
from autonomy.frames import wrap_angle
from autonomy.messages import GpsMsg, ImuMsg
from autonomy.surface.config import SurfaceAutonomyConfig
from autonomy.surface.navigation import GnssDisturbanceFilter

FloatArray = NDArray[np.float64]
BEHAVIOURS = ("station_keep", "follow")
OFFSET_FRAMES = ("track", "ned")


class SurfaceAutonomy:
    """Navigation, guidance and control of a 3-DOF surface vessel.

    Args:
        cfg: gains and limits.
        layout: the vessel's thrusters (allocation of [X, Y, 0, 0, 0, N]).
        behaviour: ``station_keep`` (hold ``station_ne_m``) or ``follow`` (hold
            ``target + offset``).
        station_ne_m: (2,) NED north/east point held in ``station_keep``, m.
        offset_ne_m: (2,) offset from the followed point, m: ``track`` frame (default):
            (along, across) its course (estimated from its successive positions; (-5, 0) is 5 m
            behind it); ``ned`` frame: (north, east).
        offset_frame: ``track`` or ``ned``.

    Raises:
        ValueError: unknown behaviour or offset frame.
    """

    def __init__(self, cfg: SurfaceAutonomyConfig, layout: ThrusterLayout, *,
                 behaviour: Literal["station_keep", "follow"] = "station_keep",
                 station_ne_m: ArrayLike = (0.0, 0.0), offset_ne_m: ArrayLike = (0.0, 0.0),
                 offset_frame: Literal["track", "ned"] = "track") -> None:
        if behaviour not in BEHAVIOURS:
            raise ValueError(f"behaviour must be one of {BEHAVIOURS}, got {behaviour!r}")
        self.cfg, self.behaviour = cfg, behaviour
        self.station_ne_m = np.asarray(station_ne_m, dtype=float).reshape(2)
        if offset_frame not in OFFSET_FRAMES:
            raise ValueError(f"offset_frame must be one of {OFFSET_FRAMES}, got {offset_frame!r}")
        self.offset_ne_m = np.asarray(offset_ne_m, dtype=float).reshape(2)
        self.offset_frame = offset_frame
        # Surge, sway and yaw only (the vessel is held level: roll/pitch moments of the
        # thrusters act on nothing); yaw weighted up so that, in saturation, the heading is
        # kept and translation gives way (else the vessel crabs at a wrong heading).
        self.allocator = ThrustAllocator.from_layout(layout, dof_weights=(1.0, 1.0, 0.0, 0.0, 0.0, 25.0))
        self.nav = GnssDisturbanceFilter(cfg.navigation, cfg.model_mass_kg, cfg.model_drag_linear_n_per_mps,
                                         cfg.model_drag_quadratic_n_per_mps2, initial_speed_sigma_mps=cfg.max_speed_mps)
        self.reset()

    def reset(self) -> None:
        self.nav.reset()
        self._t_s: float | None = None
        self._integral = np.zeros(2)
        self._force_lp = np.zeros(2)
        self._heading_sp: float | None = None
        self._target: FloatArray | None = None
        self._target_t_s = -math.inf
        self._target_vel = np.zeros(2)
        self._course_rad = 0.0
        self.goal_ne_m: FloatArray | None = None
        self.wrench_body = np.zeros(6)

    # ------------------------------------------------------------------ inputs
    def _take_target(self, t_s: float, target_pos_ned: ArrayLike | None) -> None:
        """Track the followed point's position and a low-passed velocity from its changes."""
        if target_pos_ned is None:
            return
        p = np.asarray(target_pos_ned, dtype=float).reshape(-1)[:2]
        if self._target is None:
            self._target, self._target_t_s = p.copy(), t_s
            return
        if np.array_equal(p, self._target) or t_s <= self._target_t_s:
            return
        dt = t_s - self._target_t_s
        alpha = 1.0 - math.exp(-dt / self.cfg.target_filter_tau_s)
        self._target_vel += alpha * ((p - self._target) / dt - self._target_vel)
        self._target, self._target_t_s = p.copy(), t_s
        if float(np.hypot(*self._target_vel)) >= self.cfg.min_course_speed_mps:
            self._course_rad = math.atan2(self._target_vel[1], self._target_vel[0])

    def goal(self) -> tuple[FloatArray, FloatArray] | None:
        """Point to hold (2,) and its velocity (2,), NED, or None (following, no target yet)."""
        if self.behaviour == "station_keep":
            return self.station_ne_m, np.zeros(2)
        if self._target is None:
            return None
        offset = self.offset_ne_m
        if self.offset_frame == "track":  # (along, across) the followed point's course
            c, s = math.cos(self._course_rad), math.sin(self._course_rad)
            offset = np.array([c * offset[0] - s * offset[1], s * offset[0] + c * offset[1]])
        return self._target + offset, self._target_vel

    # ------------------------------------------------------------------ the tick
    def update(self, t_s: float, gnss: Sequence[GpsMsg] = (), compass: ImuMsg | None = None,
               target_pos_ned: ArrayLike | None = None) -> FloatArray:
        """One autonomy tick.

        Args:
            t_s: time now, s.
            gnss: fixes received since the last tick (invalid ones are skipped).
            compass: latest AHRS reading (heading ``rpy_rad[2]``, yaw rate
                ``rate_body_radps[2]``); None: thrusters off.
            target_pos_ned: (2,) or (3,) latest position of the followed vehicle, NED m, or
                None (nothing new; the last one is kept). Ignored in ``station_keep``.

        Returns:
            (n_thr,) normalised thruster commands in [-1, 1] (zeros until the navigation is
            valid and, when following, a target is known).
        """
        cfg = self.cfg
        dt = 0.0 if self._t_s is None else max(t_s - self._t_s, 0.0)
        self._t_s = t_s
        self.nav.update(gnss)
        self.nav.predict(t_s)
        self._take_target(t_s, target_pos_ned)
        goal = self.goal()
        n_thr = self.allocator.config_matrix.shape[1]
        if compass is None or goal is None or not self.nav.valid(t_s):
            self.wrench_body = np.zeros(6)
            self.nav.set_input((0.0, 0.0), 0.0 if compass is None else float(compass.rpy_rad[2]))
            return np.zeros(n_thr)
        point, point_vel = goal
        self.goal_ne_m = point.copy()
        pos, vel = self.nav.pos_ne_m, self.nav.vel_ne_mps
        v_d = cfg.k_pos_per_s * (point - pos) + point_vel
        speed = float(np.hypot(*v_d))
        saturated = speed > cfg.max_speed_mps
        if saturated:
            v_d *= cfg.max_speed_mps / speed
            speed = cfg.max_speed_mps
        ev = v_d - vel
        if not saturated:  # anti-windup: no integral while catching up at full speed
            self._integral += cfg.ki_pos_per_s3 * (point - pos) * dt
        mag = float(np.hypot(*self._integral))
        if mag > cfg.integral_limit_mps2:
            self._integral *= cfg.integral_limit_mps2 / mag
        mass = cfg.model_mass_kg[0]
        drag = cfg.model_drag_linear_n_per_mps[0] * speed + cfg.model_drag_quadratic_n_per_mps2[0] * speed * speed
        # The slow part: the estimated disturbance (current drag), the integral, the drag feedforward.
        steady_ned = mass * (self._integral - self.nav.disturbance_ne_mps2)
        if speed > 0.0:
            steady_ned = steady_ned + drag * v_d / speed
        force_ned = steady_ned + mass * cfg.k_vel_per_s * ev
        alpha = 1.0 - math.exp(-dt / cfg.force_filter_tau_s) if dt > 0.0 else 1.0
        self._force_lp += alpha * (steady_ned - self._force_lp)
        heading = float(compass.rpy_rad[2])
        if float(np.hypot(*self._force_lp)) > cfg.min_heading_force_n:
            self._heading_sp = math.atan2(self._force_lp[1], self._force_lp[0])
        elif self._heading_sp is None:
            self._heading_sp = heading
        c, s = math.cos(heading), math.sin(heading)
        fx = c * force_ned[0] + s * force_ned[1]
        fy = -s * force_ned[0] + c * force_ned[1]
        wn, zeta = cfg.yaw_bandwidth_radps, cfg.yaw_damping_ratio
        yaw_err = float(wrap_angle(self._heading_sp - heading))
        n_moment = cfg.yaw_inertia_kgm2 * (wn * wn * yaw_err - 2.0 * zeta * wn * float(compass.rate_body_radps[2]))
        self.wrench_body = np.array([fx, fy, 0.0, 0.0, 0.0, n_moment])
        cmd = self.allocator.allocate(self.wrench_body)
        # What the thrusters will deliver (saturation included) is the filter's input.
        achieved = self.allocator.config_matrix @ command_to_thrust(cmd, self.allocator.layout)
        self.nav.set_input(achieved[:2], heading)
        return cmd
