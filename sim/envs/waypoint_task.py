"""The Waypoint task: reach a sequence of 3-D waypoints under a random current.

One implementation behind both interfaces: the gymnasium env ``auvsim/Waypoint-v1``
(:mod:`sim.envs.waypoint_env`) and the dm_control one (:mod:`sim.envs.dm`). A decision is
three phases, :meth:`WaypointTask.begin_step` (action in), :meth:`WaypointTask.advance`
(the simulation over one decision interval) and :meth:`WaypointTask.end_step` (reward,
termination, observation): the gymnasium env calls them through
:meth:`WaypointTask.step`, the dm_control task from ``before_step``, the physics' ``step``
and ``after_step``, in the same order, so both give the same trajectory bit for bit.

A light loop without sonar, sensors or navigation filter, for fast RL baselines: MuJoCo
physics with the Fossen wrench (:class:`sim.dynamics.vehicle.VehicleDynamics`) and thruster
dynamics, driven either by a body-wrench action through the thrust allocation or by
speed/yaw-rate/depth setpoints through the autopilots. Observations come from the true
vehicle state (no sensor noise).

Each episode draws from the generator given to :meth:`WaypointTask.reset`: a start pose inside the
scenario's survey area, ``n_waypoints`` waypoints in that area and the depth band, and a
horizontal current of up to ``current_speed_max_mps`` added to the scenario's current.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from autonomy.control.allocation import ThrustAllocator
from autonomy.control.autopilot import Autopilot
from autonomy.control.setpoint import Setpoint
from autonomy.frames import wrap_angle
from autonomy.messages import NavEstimate
from scenarios.config.world import CurrentConfig
from scenarios.schema import Scenario
from sim.envs.area import OperatingArea, survey_area
from sim.envs.action_check import checked_action
from sim.envs.scenario_arg import resolve_scenario
from sim.envs.time_limit import reached_time_limit, time_limit_steps
from sim.scene.physics import Physics

ACTION_MODES = ("wrench", "setpoint")

_POS_LIMIT_M = 200.0
_VEL_LIMIT = 5.0


@dataclass(frozen=True)
class WaypointRewardWeights:
    """Reward per decision step: ``progress_per_m * (d_prev - d_now) + waypoint_bonus *
    reached - energy_per_s * mean(cmd^2) * dt - time_per_s * dt``, minus ``collision`` or
    ``leave_area`` on those terminations (cmd: normalised thruster commands)."""

    progress_per_m: float = 1.0
    waypoint_bonus: float = 10.0
    energy_per_s: float = 0.1
    time_per_s: float = 0.05
    collision: float = 50.0
    leave_area: float = 50.0


@dataclass(frozen=True)
class WaypointEnvOptions:
    """Typed options of :class:`WaypointEnv`.

    Attributes:
        decision_interval_s: time one action is held, s (a multiple of the physics step).
        physics_rate_hz: physics rate override (None: the scenario's). 50 Hz is the
            default: trajectories match 200 Hz to centimetres over a minute
            (``tests/sim/envs/test_waypoint_env.py``) at 4x less cost.
        action_mode: ``wrench``: normalised body wrench [X, Y, Z, N] in [-1, 1] scaled by the
            autopilots' output limits, allocated to the thrusters; ``setpoint``: normalised
            [surge speed in speed_range_mps, yaw rate in +-max yaw rate, depth in
            depth_range_m] tracked by the scenario's autopilots.
        n_waypoints: waypoints per episode.
        acceptance_radius_m: a waypoint is reached inside this 3-D distance.
        depth_range_m: (min, max) depth of start and waypoints, m.
        speed_range_mps: (min, max) speed setpoint (setpoint mode).
        current_speed_max_mps: bound of the random horizontal current added per episode.
        max_episode_s: time limit (truncation), s.
        area_margin_m: the episode ends if the vehicle goes this far outside the area.
        reward: reward weights.
    """

    decision_interval_s: float = 0.1
    physics_rate_hz: float | None = 50.0
    action_mode: Literal["wrench", "setpoint"] = "wrench"
    n_waypoints: int = 3
    acceptance_radius_m: float = 1.0
    depth_range_m: tuple[float, float] = (1.0, 3.0)
    speed_range_mps: tuple[float, float] = (0.0, 1.0)
    current_speed_max_mps: float = 0.2
    max_episode_s: float = 120.0
    area_margin_m: float = 10.0
    reward: WaypointRewardWeights = field(default_factory=WaypointRewardWeights)

    def __post_init__(self) -> None:
        if self.action_mode not in ACTION_MODES:
            raise ValueError(f"WaypointEnvOptions.action_mode must be one of {ACTION_MODES}, got {self.action_mode!r}")
        if not self.decision_interval_s > 0.0:
            raise ValueError(f"WaypointEnvOptions.decision_interval_s must be > 0, got {self.decision_interval_s}")
        if self.physics_rate_hz is not None and not 20.0 <= self.physics_rate_hz <= 5000.0:
            raise ValueError(f"WaypointEnvOptions.physics_rate_hz must be in [20, 5000] or None, got {self.physics_rate_hz}")
        if self.n_waypoints < 1:
            raise ValueError(f"WaypointEnvOptions.n_waypoints must be >= 1, got {self.n_waypoints}")
        lo, hi = self.depth_range_m
        if not 0.0 < lo <= hi:
            raise ValueError(f"WaypointEnvOptions.depth_range_m must satisfy 0 < min <= max, got {self.depth_range_m}")
        s_lo, s_hi = self.speed_range_mps
        if not 0.0 <= s_lo < s_hi:
            raise ValueError(f"WaypointEnvOptions.speed_range_mps must satisfy 0 <= min < max, got {self.speed_range_mps}")
        for name in ("acceptance_radius_m", "max_episode_s"):
            if not getattr(self, name) > 0.0:
                raise ValueError(f"WaypointEnvOptions.{name} must be > 0, got {getattr(self, name)}")
        for name in ("current_speed_max_mps", "area_margin_m"):
            if not getattr(self, name) >= 0.0:
                raise ValueError(f"WaypointEnvOptions.{name} must be >= 0, got {getattr(self, name)}")


def _options(options: WaypointEnvOptions | dict | None) -> WaypointEnvOptions:
    if options is None:
        return WaypointEnvOptions()
    if isinstance(options, dict):
        opts = dict(options)
        if isinstance(opts.get("reward"), dict):
            opts["reward"] = WaypointRewardWeights(**opts["reward"])
        return WaypointEnvOptions(**opts)
    return options


class WaypointTask:
    """Reach waypoints under currents (no sonar): the task logic, free of any RL interface.

    The gymnasium and dm_control wrappers hold one instance and only translate its results
    (both through the phases :meth:`begin_step`, :meth:`advance`, :meth:`end_step`), so
    both give the same trajectory for the same seed and actions, bit for bit.

    Observation (float32 vector, shape ``(obs_size,)`` = ``(20 + n_act,)``): current waypoint
    relative to the vehicle in the level body frame [forward, starboard, down] (m), the next
    one likewise (m), 3-D distance to the current waypoint (m), sin/cos yaw, roll, pitch
    (rad), body velocity [u, v, w] (m/s) and [p, q, r] (rad/s) in FRD, depth (m, NED z),
    altitude above the seabed (m), fraction of waypoints left, and the previous action.
    Values are clipped to [``obs_low``, ``obs_high``].

    Action (shape ``(n_act,)``, in [-1, 1]): see :class:`WaypointEnvOptions.action_mode`.

    No episode ends by leaving the water: the hull cannot. Near the surface its buoyancy is
    scaled by its submerged fraction (:func:`sim.dynamics.hydrodynamics.submerged_fraction`), so a
    positively buoyant hull floats with its origin below the surface; lifting the origin out
    needs an upward thrust above ``W - B f0`` (``f0`` the submerged fraction with the origin
    at the surface): about 170 N for FeelHippo, 65 N for the BlueROV2 Heavy. The heave, in
    either action mode (and in the Survey task), is the depth autopilot's
    ``autonomy.control.depth.output_limit``, 20 N by default, so the hull floats (FeelHippo's
    origin about 0.17 m deep at full up heave). An origin above the surface would count as
    leaving the area (a scenario raising that limit).

    Args:
        scenario: shipped scenario name, YAML path or :class:`Scenario`.
        options: typed options, or a dict of them (``reward`` may be a dict too).
        overrides: ``key.path=value`` scenario overrides.

    Raises:
        ValueError: inconsistent options (decision interval not a multiple of the physics
            step, depth band too close to the seabed, non-finite wrench limits).
        scenarios.load.ScenarioError: a bad scenario or override.
    """

    def __init__(self, scenario: str | Path | Scenario = "cssn_lawnmower",
                 options: WaypointEnvOptions | dict | None = None, overrides: tuple[str, ...] = ()) -> None:
        self.options = opts = _options(options)
        over = list(overrides)
        if opts.physics_rate_hz is not None:
            over.append(f"physics.rate_hz={opts.physics_rate_hz}")
        self.scenario = scn = resolve_scenario(scenario, over)
        self.area: OperatingArea = survey_area(scn, opts.area_margin_m)
        self.physics = Physics(scn)
        self.params = self.physics.params
        self.world = self.physics.world
        self.dt_s = self.physics.dt_s
        self.substeps = int(round(opts.decision_interval_s / self.dt_s))
        if self.substeps < 1 or abs(self.substeps * self.dt_s - opts.decision_interval_s) > 1e-6:
            raise ValueError(f"WaypointEnvOptions.decision_interval_s={opts.decision_interval_s} must be a multiple "
                             f"of the physics step {self.dt_s} s (physics_rate_hz={1.0 / self.dt_s:g})")
        self.decision_interval_s = self.substeps * self.dt_s
        seabed_min = float(np.min(self.world.seabed.depth_at(
            *np.meshgrid(np.linspace(self.area.lo_ne_m[0], self.area.hi_ne_m[0], 9),
                         np.linspace(self.area.lo_ne_m[1], self.area.hi_ne_m[1], 9)))))
        if opts.depth_range_m[1] > seabed_min - 0.5:
            raise ValueError(f"WaypointEnvOptions.depth_range_m max {opts.depth_range_m[1]} m must stay 0.5 m above "
                             f"the shallowest seabed in the area ({seabed_min:.2f} m)")
        self.allocator = ThrustAllocator.from_layout(self.params.layout)
        ctrl = scn.autonomy.control
        self.autopilot = Autopilot(ctrl)
        self.autopilot_dt_s = 1.0 / scn.autonomy.rate_hz
        self.max_yaw_rate_radps = math.radians(ctrl.max_yaw_rate_dps)
        self.wrench_scale = np.array([ctrl.surge.output_limit, ctrl.sway.output_limit, ctrl.depth.output_limit,
                                      ctrl.heading.output_limit], dtype=float)
        if not np.all(np.isfinite(self.wrench_scale)):
            raise ValueError("WaypointEnv wrench mode needs finite autonomy.control.{surge,sway,depth,heading}."
                             "output_limit (they scale the action)")
        self.n_act = 4 if opts.action_mode == "wrench" else 3
        hi = np.array([_POS_LIMIT_M] * 7 + [1.0, 1.0, math.pi, math.pi] + [_VEL_LIMIT] * 6 + [100.0, 100.0, 1.0]
                      + [1.0] * self.n_act, dtype=np.float32)
        lo = -hi.copy()
        lo[6] = 0.0
        lo[17:20] = 0.0
        self.obs_low, self.obs_high = lo, hi
        self.obs_size = int(hi.size)
        self._t_s = 0.0
        self._n_steps = 0
        self._waypoints = np.zeros((opts.n_waypoints, 3))
        self._wp_index = 0
        self._prev_action = np.zeros(self.n_act)
        self._thruster_cmd = np.zeros(self.params.n_thrusters)
        self._action = np.zeros(self.n_act)
        self._collided, self._effort, self._n_advanced = False, 0.0, 0
        self._heading_sp_rad = 0.0

    # ------------------------------------------------------------------ state views
    @property
    def t_s(self) -> float:
        """Time since the episode's start, s: the decision clock, decisions x
        ``decision_interval_s``."""
        return self._t_s

    @property
    def sim_physics(self) -> Physics:
        """The simulation this task advances (its MuJoCo ``model`` / ``data`` are what the
        dm_control physics :class:`sim.envs.dm_physics.AuvPhysics` wraps); the same object
        for every episode."""
        return self.physics

    @property
    def time_limit_steps(self) -> int:
        """The decision at which an episode is truncated (``max_episode_s`` reached,
        :func:`sim.envs.time_limit.reached_time_limit`)."""
        return time_limit_steps(self.decision_interval_s, self.options.max_episode_s)

    @property
    def pos_ned(self) -> np.ndarray:
        """(3,) true vehicle position, NED, m (a copy)."""
        return self._pos.copy()

    @property
    def rpy_rad(self) -> np.ndarray:
        """(3,) true roll, pitch, yaw (ZYX), rad (a copy)."""
        return self._rpy.copy()

    @property
    def heading_setpoint_rad(self) -> float:
        """Heading the setpoint-mode autopilot tracks, rad (NED yaw)."""
        return self._heading_sp_rad

    def waypoint_ned(self) -> np.ndarray:
        """(3,) the waypoint being sought (the last one once all are reached), NED, m."""
        return self._waypoints[min(self._wp_index, self.options.n_waypoints - 1)].copy()

    # ------------------------------------------------------------------ episode
    def _draw_point(self, rng: np.random.Generator) -> np.ndarray:
        ne = rng.uniform(self.area.lo_ne_m, self.area.hi_ne_m)
        return np.array([ne[0], ne[1], rng.uniform(*self.options.depth_range_m)])

    def reset(self, rng: np.random.Generator) -> tuple[np.ndarray, dict[str, Any]]:
        """Start an episode drawn from ``rng`` (start pose, waypoints, current).

        Returns:
            ``(observation (obs_size,) float32, info)``; info as :meth:`step`'s, without ``energy``.
        """
        opts = self.options
        start = self._draw_point(rng)
        yaw = float(rng.uniform(-math.pi, math.pi))
        self._waypoints = np.array([self._draw_point(rng) for _ in range(opts.n_waypoints)])
        speed = float(rng.uniform(0.0, opts.current_speed_max_mps))
        direction = float(rng.uniform(-math.pi, math.pi))
        base = self.scenario.world.current
        vel = (base.velocity_ned_mps[0] + speed * math.cos(direction),
               base.velocity_ned_mps[1] + speed * math.sin(direction), base.velocity_ned_mps[2])
        current_cfg = base.model_copy(update={"velocity_ned_mps": vel})
        current_rng = np.random.default_rng(int(rng.integers(0, 2**63 - 1)))
        self.physics.set_current(CurrentConfig.model_validate(current_cfg.model_dump()), current_rng)
        self.physics.reset(start, (0.0, 0.0, yaw))
        self.autopilot.reset()
        self._heading_sp_rad = yaw
        self._t_s = 0.0
        self._n_steps = 0
        self._wp_index = 0
        self._prev_action = np.zeros(self.n_act)
        self._thruster_cmd = np.zeros(self.params.n_thrusters)
        self._action = np.zeros(self.n_act)
        self._collided, self._effort, self._n_advanced = False, 0.0, 0
        self._pos, self._R, self._rpy, self._nu = self._state()
        self._dist = float(np.linalg.norm(self._waypoints[0] - self._pos))
        return self._observation(), self._info(False, False)

    def _state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        truth = self.physics.truth()
        return truth.pos_ned, truth.R_nb, truth.rpy_rad, truth.nu

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Hold ``action`` (shape ``(n_act,)``, clipped to [-1, 1]) for one decision interval:
        :meth:`begin_step`, :meth:`advance`, :meth:`end_step`, the phases the dm_control
        task (:mod:`sim.envs.dm`) calls in the same order.

        Returns:
            ``(observation, reward, terminated, truncated, info)``: terminated when every
            waypoint is reached, on a collision, or on leaving the area (``area_margin_m``
            past it); truncated at ``max_episode_s`` (decision :attr:`time_limit_steps`).
            The hull cannot leave the water (see the class docstring). info: ``t_s``,
            ``waypoints_reached``, ``distance_m``, ``collision``, ``left_area``, ``pos_ned``
            (3,) m, ``energy`` (integral of the mean squared normalised thruster command, s).

        Raises:
            ValueError: an action of another shape, or with NaN or an infinity.
        """
        self.begin_step(action)
        self.advance()
        return self.end_step()

    def begin_step(self, action: np.ndarray) -> None:
        """Phase 1 of :meth:`step`: check and clip ``action`` (shape ``(n_act,)``, to [-1, 1]),
        hold it (wrench mode: allocate the thruster commands now) and zero the step's
        collision flag and energy.

        Raises:
            ValueError: an action of another shape, or with NaN or an infinity (nothing is changed then).
        """
        a = checked_action(action, self.n_act, "WaypointTask.step")
        if self.options.action_mode == "wrench":
            wrench = np.zeros(6)
            wrench[[0, 1, 2, 5]] = a * self.wrench_scale
            self._thruster_cmd = self.allocator.allocate(wrench)
        self._action = a
        self._collided = False
        self._effort = 0.0
        self._n_advanced = 0

    def advance(self) -> None:
        """Phase 2 of :meth:`step`: one decision interval of simulation (``substeps`` physics
        steps of :meth:`sim.scene.physics.Physics.advance`: thrusters, Fossen wrench, MuJoCo,
        current) holding the action of the latest :meth:`begin_step` (zeros after
        :meth:`reset`); setpoint mode runs the autopilots at the autonomy rate. Advances
        the decision clock :attr:`t_s` by ``decision_interval_s``, accumulates contact and
        energy for :meth:`end_step`."""
        opts = self.options
        a = self._action
        collided = self._collided
        effort = self._effort
        ticks_per_control = max(int(round(self.autopilot_dt_s / self.dt_s)), 1)
        ticks = self.substeps if opts.action_mode == "wrench" else ticks_per_control
        for k in range(0, self.substeps, ticks):
            if opts.action_mode == "setpoint":
                self._thruster_cmd = self._setpoint_command(a, ticks_per_control * self.dt_s)
            n = min(ticks, self.substeps - k)
            collided |= self.physics.advance(self._thruster_cmd, n)
            effort += float(np.mean(np.square(self._thruster_cmd))) * self.dt_s * n
        self._collided = collided
        self._effort = effort
        self._n_advanced += 1
        self._n_steps += 1
        self._t_s = self._n_steps * self.decision_interval_s
        self._pos, self._R, self._rpy, self._nu = self._state()

    def end_step(self) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Phase 3 of :meth:`step`: reward, termination, observation and info of the
        decision intervals advanced since :meth:`begin_step` (one in :meth:`step`).

        Returns:
            as :meth:`step`.
        """
        opts, w = self.options, self.options.reward
        collided, effort = self._collided, self._effort
        reward = -w.energy_per_s * effort - w.time_per_s * (self._n_advanced * self.decision_interval_s)
        dist = float(np.linalg.norm(self._waypoints[self._wp_index] - self._pos))
        reward += w.progress_per_m * (self._dist - dist)
        if dist <= opts.acceptance_radius_m:
            reward += w.waypoint_bonus
            self._wp_index += 1
            if self._wp_index < opts.n_waypoints:
                dist = float(np.linalg.norm(self._waypoints[self._wp_index] - self._pos))
        self._dist = dist
        finished = self._wp_index >= opts.n_waypoints
        left = bool(not self.area.contains(self._pos) or self._pos[2] < 0.0)  # z < 0: out of reach (class docstring)
        if collided:
            reward -= w.collision
        if left:
            reward -= w.leave_area
        terminated = finished or collided or left
        truncated = (not terminated) and reached_time_limit(self._n_steps, self.decision_interval_s,
                                                            opts.max_episode_s)
        self._prev_action = self._action
        info = self._info(collided, left)
        info["energy"] = effort
        return self._observation(), float(reward), terminated, truncated, info

    def _setpoint_command(self, a: np.ndarray, dt_s: float) -> np.ndarray:
        opts = self.options
        s_lo, s_hi = opts.speed_range_mps
        d_lo, d_hi = opts.depth_range_m
        speed = s_lo + 0.5 * (a[0] + 1.0) * (s_hi - s_lo)
        self._heading_sp_rad = float(wrap_angle(self._heading_sp_rad + a[1] * self.max_yaw_rate_radps * dt_s))
        depth = d_lo + 0.5 * (a[2] + 1.0) * (d_hi - d_lo)
        truth = self.physics.truth()
        nav = NavEstimate(t_s=self._t_s, pos_ned=truth.pos_ned, rpy_rad=truth.rpy_rad, vel_body_mps=truth.nu[:3],
                          rate_body_radps=truth.nu[3:], cov_pos_ned=np.zeros((3, 3)))
        wrench = self.autopilot.update(nav, Setpoint(float(speed), self._heading_sp_rad, depth_m=float(depth)), dt_s)
        return self.allocator.allocate(wrench)

    # ------------------------------------------------------------------ observation
    def _observation(self) -> np.ndarray:
        yaw = float(self._rpy[2])
        c, s = math.cos(yaw), math.sin(yaw)
        i = min(self._wp_index, self.options.n_waypoints - 1)
        j = min(i + 1, self.options.n_waypoints - 1)

        def level_body(p: np.ndarray) -> list[float]:
            d = p - self._pos
            return [c * d[0] + s * d[1], -s * d[0] + c * d[1], d[2]]

        depth = float(self._pos[2])
        altitude = float(self.world.seabed.depth_at(self._pos[0], self._pos[1])) - depth
        left = (self.options.n_waypoints - self._wp_index) / self.options.n_waypoints
        obs = np.array(level_body(self._waypoints[i]) + level_body(self._waypoints[j]) + [self._dist, s, c]
                       + [float(self._rpy[0]), float(self._rpy[1])] + list(self._nu) + [depth, altitude, left]
                       + list(self._prev_action), dtype=np.float32)
        return np.clip(obs, self.obs_low, self.obs_high)

    def _info(self, collided: bool, left: bool) -> dict[str, Any]:
        return {"t_s": self._t_s, "waypoints_reached": self._wp_index, "distance_m": self._dist,
                "collision": collided, "left_area": left, "pos_ned": self._pos.copy()}
