"""The Survey task: find and localise the targets of an area with high-level setpoints.

One implementation behind both interfaces: the gymnasium env ``auvsim/Survey-v1``
(:mod:`sim.envs.survey_env`) and the dm_control one (:mod:`sim.envs.dm`), both through
the phases :meth:`SurveyTask.begin_step`, :meth:`SurveyTask.advance` and
:meth:`SurveyTask.end_step` in the same order (:meth:`SurveyTask.step` runs them for
gymnasium).

Each episode (:mod:`sim.envs.survey_layout`) surveys a square area larger than the sonar's
reach (``area_size_ne_m``, 80 m x 80 m by default, centred on the scenario's survey plan),
starting at its south-west corner heading north, with the scenario's objects placed at
random in the area from the generator given to :meth:`SurveyTask.reset`, none within the
sonar's reach of the start. (``Survey-v0`` surveyed the scenario's own small area with its
fixed targets: the start already saw every target, so every sonar episode ended on its
first step.)

Wraps the closed-loop :class:`sim.mission.Mission` (physics, navigation sensors, EKF,
autopilots and, with ``sonar=True``, the FLS, ATR, geolocalisation and PMHA world model).
The agent replaces the mission's guidance: each action sets surge speed, yaw rate and
altitude for one decision interval; the autopilots track them at the autonomy rate.

Coverage is computed onboard: a coarse grid over the survey area whose cells are marked
once the sonar fan, at the navigation estimate's poses, has swept most of the cell's
(mapped) seabed (``coverage_samples_per_side`` squared points per cell, at least
``coverage_min_seen_fraction`` of them; :class:`sim.envs.coverage.CoverageGrid`). The ground
in the FLS's near-range blind zone (under and just ahead of the vehicle) is never seen
there; it counts once the fan's near edge swept it on the way. Targets count as found when a confirmed world-model object (enough
supporting detections) lies within ``match_radius_m`` of a true target.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from autonomy.control.setpoint import Setpoint
from autonomy.frames import wrap_angle
from autonomy.messages import NavEstimate
from scenarios.schema import Scenario
from sim.envs.area import OperatingArea
from sim.envs.coverage import CoverageGrid
from sim.envs.action_check import checked_action
from sim.envs.scenario_arg import resolve_scenario
from sim.envs.time_limit import reached_time_limit, time_limit_steps
from sim.envs.survey_layout import SurveyLayout, episode_scenario, episode_seabed, make_layout
from sim.envs.world_model_obs import anchor_bounds, anchor_table, match_new_targets
from sim.mission import Mission
from sim.events.records import MissionInfo, MissionSummary, ObserverBase
from sim.scene.physics import Physics
from sim.scene.seabed import Seabed
from sim.sensors.base import Mount
from sim.sensors.fls import FlsRender
from scenarios.fls_presets import resolve_geometry


NAV_FEATURES = ("n_m", "e_m", "depth_m", "altitude_m", "altitude_valid", "roll_rad", "pitch_rad", "sin_yaw",
                "cos_yaw", "u_mps", "v_mps", "w_mps", "r_radps", "pos_sigma_m", "time_fraction",
                "coverage_fraction")
_NAV_HI = np.array([200.0, 200.0, 100.0, 100.0, 1.0, math.pi, math.pi, 1.0, 1.0, 5.0, 5.0, 5.0, 5.0, 100.0,
                    1.0, 1.0], dtype=np.float32)
_NAV_LO = np.array([-200.0, -200.0, -10.0, 0.0, 0.0, -math.pi, -math.pi, -1.0, -1.0, -5.0, -5.0, -5.0, -5.0,
                    0.0, 0.0, 0.0], dtype=np.float32)


@dataclass(frozen=True)
class SurveyRewardWeights:
    """Reward per decision step: ``target * new targets found + coverage * new covered
    fraction of the area - energy_per_s * mean(cmd^2) * dt``, minus ``collision`` or
    ``leave_area`` on those terminations, plus ``complete`` when the mission completes."""

    target: float = 10.0
    coverage: float = 10.0
    energy_per_s: float = 0.02
    collision: float = 50.0
    leave_area: float = 50.0
    complete: float = 10.0


@dataclass(frozen=True)
class SurveyEnvOptions:
    """Typed options of the Survey task (:class:`SurveyTask`, ``SurveyEnv``).

    Attributes:
        sonar: simulate the FLS and run ATR + PMHA, and add the downsampled fan image
            (``obs["sonar"]``); False: no sonar at all (fast; the world model stays empty,
            coverage still uses the sonar's nominal fan).
        decision_interval_s: time one action is held (a multiple of the autonomy period).
        max_episode_s: time limit (None: the scenario's duration).
        top_k_anchors: rows of the world-model table.
        coverage_shape: (rows, cols) of the coverage grid over the survey area.
        coverage_samples_per_side, coverage_min_seen_fraction: a cell is covered once at
            least this fraction of its ``samples_per_side`` squared seabed points has been
            inside the fan (1 and any fraction: its centre alone, which a cell entered from
            the side into the near-range blind zone never reaches).
        sonar_shape: (height, width) of the downsampled fan image.
        speed_range_mps, altitude_range_m: what action -1 .. 1 maps to.
        complete_coverage_fraction: the mission is complete at this covered fraction
            (or once every target is found, with sonar).
        match_radius_m: a world object within this of a true target finds it.
        area_margin_m: the episode ends this far outside the survey area.
        area_size_ne_m: (north, east) size of the surveyed square, m; must exceed the sonar's
            reach.
        start_clearance_m: no object is placed closer than this to the start (None: the
            sonar's far range + 5 m).
        min_target_spacing_m: objects are placed at least this far apart, m.
        nav_source: pose used for target geolocalisation (``estimate`` or ``truth``).
        physics_rate_hz: physics rate override (None: the scenario's).
        reward: reward weights.
    """

    sonar: bool = True
    decision_interval_s: float = 1.0
    max_episode_s: float | None = None
    top_k_anchors: int = 16
    coverage_shape: tuple[int, int] = (16, 16)
    coverage_samples_per_side: int = 3
    coverage_min_seen_fraction: float = 0.5
    sonar_shape: tuple[int, int] = (64, 64)
    speed_range_mps: tuple[float, float] = (0.0, 1.0)
    altitude_range_m: tuple[float, float] = (1.0, 3.0)
    complete_coverage_fraction: float = 0.95
    match_radius_m: float = 2.0
    area_margin_m: float = 5.0
    area_size_ne_m: tuple[float, float] = (80.0, 80.0)
    start_clearance_m: float | None = None
    min_target_spacing_m: float = 4.0
    nav_source: str = "estimate"
    physics_rate_hz: float | None = None
    reward: SurveyRewardWeights = field(default_factory=SurveyRewardWeights)

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            _check_option_type(f.name, f.type, getattr(self, f.name))
        if not self.decision_interval_s > 0.0:
            raise ValueError(f"SurveyEnvOptions.decision_interval_s must be > 0, got {self.decision_interval_s}")
        if self.max_episode_s is not None and not self.max_episode_s > 0.0:
            raise ValueError(f"SurveyEnvOptions.max_episode_s must be > 0 or None, got {self.max_episode_s}")
        if self.top_k_anchors < 1:
            raise ValueError(f"SurveyEnvOptions.top_k_anchors must be >= 1, got {self.top_k_anchors}")
        for name in ("coverage_shape", "sonar_shape"):
            shape = getattr(self, name)
            if len(shape) != 2 or min(shape) < 1:
                raise ValueError(f"SurveyEnvOptions.{name} must be two positive ints, got {shape}")
        if self.coverage_samples_per_side < 1:
            raise ValueError(f"SurveyEnvOptions.coverage_samples_per_side must be >= 1, "
                             f"got {self.coverage_samples_per_side}")
        if not 0.0 < self.coverage_min_seen_fraction <= 1.0:
            raise ValueError(f"SurveyEnvOptions.coverage_min_seen_fraction must be in (0, 1], "
                             f"got {self.coverage_min_seen_fraction}")
        if not 0.0 <= self.speed_range_mps[0] < self.speed_range_mps[1]:
            raise ValueError(f"SurveyEnvOptions.speed_range_mps must satisfy 0 <= min < max, got {self.speed_range_mps}")
        if not 0.0 < self.altitude_range_m[0] <= self.altitude_range_m[1]:
            raise ValueError(f"SurveyEnvOptions.altitude_range_m must satisfy 0 < min <= max, got {self.altitude_range_m}")
        if not 0.0 < self.complete_coverage_fraction <= 1.0:
            raise ValueError("SurveyEnvOptions.complete_coverage_fraction must be in (0, 1], "
                             f"got {self.complete_coverage_fraction}")
        if not self.match_radius_m > 0.0 or not self.area_margin_m >= 0.0:
            raise ValueError("SurveyEnvOptions.match_radius_m must be > 0 and area_margin_m >= 0")
        if len(self.area_size_ne_m) != 2 or min(self.area_size_ne_m) <= 0.0:
            raise ValueError(f"SurveyEnvOptions.area_size_ne_m must be two sizes > 0, got {self.area_size_ne_m}")
        if self.start_clearance_m is not None and not self.start_clearance_m >= 0.0:
            raise ValueError(f"SurveyEnvOptions.start_clearance_m must be >= 0 or None, got {self.start_clearance_m}")
        if not self.min_target_spacing_m >= 0.0:
            raise ValueError(f"SurveyEnvOptions.min_target_spacing_m must be >= 0, got {self.min_target_spacing_m}")


def is_int(v: Any) -> bool:
    """An integer (Python or numpy), not a bool."""
    return isinstance(v, int | np.integer) and not isinstance(v, bool | np.bool_)


def _is_number(v: Any) -> bool:
    return isinstance(v, int | float | np.integer | np.floating) and not isinstance(v, bool | np.bool_)


def _is_pair(v: Any) -> bool:
    return isinstance(v, tuple) and len(v) == 2 and all(_is_number(x) for x in v)


#: A ``SurveyEnvOptions`` field's declared type (``| None`` aside) -> (check, what is allowed).
_OPTION_KINDS = {
    "bool": (lambda v: isinstance(v, bool | np.bool_), "True or False"),
    "int": (is_int, "an integer"),
    "float": (_is_number, "a number"),
    "str": (lambda v: isinstance(v, str), "a string"),
    "tuple[int, int]": (_is_pair, "two numbers"),
    "tuple[float, float]": (_is_pair, "two numbers"),
}


def _check_option_type(name: str, annotation: str, value: Any) -> None:
    """Raise ValueError naming ``SurveyEnvOptions.<name>`` when ``value`` is not of its
    declared kind (:data:`_OPTION_KINDS`; fields of other types are checked where they are used)."""
    optional = annotation.endswith(" | None")
    kind = _OPTION_KINDS.get(annotation.removesuffix(" | None"))
    if kind is None or (optional and value is None):
        return
    check, allowed = kind
    if not check(value):
        raise ValueError(f"SurveyEnvOptions.{name} must be {allowed}{' (or None)' if optional else ''}, got {value!r}")


def _options(options: SurveyEnvOptions | dict | None) -> SurveyEnvOptions:
    if options is None:
        return SurveyEnvOptions()
    if isinstance(options, dict):
        opts = dict(options)
        known = {f.name for f in dataclasses.fields(SurveyEnvOptions)}
        unknown = sorted(set(opts) - known)
        if unknown:
            close = difflib.get_close_matches(unknown[0], sorted(known), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ValueError(f"SurveyEnvOptions: unknown option {unknown[0]!r}{hint}; allowed: {', '.join(sorted(known))}")
        if isinstance(opts.get("reward"), dict):
            opts["reward"] = SurveyRewardWeights(**opts["reward"])
        for key in ("coverage_shape", "sonar_shape", "speed_range_mps", "altitude_range_m", "area_size_ne_m"):
            if key in opts:
                opts[key] = tuple(opts[key])
        return SurveyEnvOptions(**opts)
    if not isinstance(options, SurveyEnvOptions):
        raise ValueError(f"options must be a SurveyEnvOptions, a dict of its fields or None, got {options!r}")
    return options


def require_fls(scn: Scenario) -> None:
    """The Survey task's layout (area larger than the sonar's reach, lawnmower spacing) and
    its coverage grid are built on the FLS entry ``sensors.fls``, also with ``sonar=False``
    (then its nominal fan, not rendered).

    Raises:
        ValueError: the scenario has no ``sensors.fls`` entry of kind ``fls``, naming the
            scenario and what to use instead.
    """
    cfg = scn.sensors.get("fls")
    if cfg is None or cfg.kind != "fls":
        what = "no sensors.fls entry" if cfg is None else f"a sensors.fls entry of kind {cfg.kind!r}"
        raise ValueError(f"scenario {scn.name!r} has {what}: the Survey task's area, lawnmower plan and coverage "
                         "(also with sonar=False) follow a forward-looking sonar's fan; use a scenario with one "
                         "(cssn_lawnmower) or add sensors.fls (kind fls)")


class _LatestFls(ObserverBase):
    """Mission observer keeping the latest fan image of the sonar named ``name``."""

    sonar_truth = False  # keeps the fan image only

    def __init__(self, name: str = "fls") -> None:
        self.name = name
        self.fan: np.ndarray | None = None

    def on_start(self, info: MissionInfo) -> None:
        self.fan = None

    def on_step(self, record) -> None:
        pass

    def on_message(self, name: str, msg: Any) -> None:
        if name == self.name and isinstance(msg, FlsRender):
            self.fan = msg.frame.fan

    def on_end(self, summary: MissionSummary) -> None:
        pass


@dataclass(frozen=True)
class ObsField:
    """One entry of the Survey observation dict: shape, dtype and elementwise bounds
    (scalars or arrays broadcastable to ``shape``)."""

    shape: tuple[int, ...]
    dtype: type
    low: float | NDArray
    high: float | NDArray


class SurveyTask:
    """Survey an area for targets (see the module docstring): the task logic, free of any RL
    interface. The gymnasium and dm_control wrappers hold one instance and only translate its
    results, so both give the same trajectory for the same seed and actions, bit for bit.

    Action (shape ``(3,)``, in [-1, 1], clipped): surge speed (mapped to
    ``speed_range_mps``, m/s), yaw rate (mapped to +- the autopilot's max yaw rate; the
    heading setpoint integrates it) and altitude above the seabed (mapped to
    ``altitude_range_m``, m).

    Observation (dict, fields in :attr:`obs_fields`): ``nav`` float32 ``(16,)``
    (:data:`NAV_FEATURES`: north/east of the navigation estimate relative to the area centre
    (m, NED), depth (m), altitude (m) and whether it is valid, roll, pitch (rad), sin/cos
    yaw, body velocity [u, v, w] (m/s, FRD), yaw rate r (rad/s), horizontal position sigma
    (m), elapsed fraction of the time limit, covered fraction of the area); ``anchors``
    float32 ``(top_k_anchors, len(ANCHOR_FEATURES))`` (top-K world objects, features
    :data:`sim.envs.world_model_obs.ANCHOR_FEATURES`, positions relative to the area centre,
    NED m); ``anchor_mask`` int8 ``(top_k_anchors,)`` in {0, 1} (rows in use); ``coverage``
    float32 ``coverage_shape`` in {0, 1} (row 0 = south, column 0 = west); and, with sonar,
    ``sonar`` uint8 ``sonar_shape`` (the latest FLS fan image, area-downsampled; zeros
    before the first frame).

    Args:
        scenario: shipped scenario name, YAML path or :class:`Scenario`.
        options: typed options, or a dict of them (``reward`` may be a dict too).
        overrides: ``key.path=value`` scenario overrides.

    Attributes (per episode, rebuilt by :meth:`reset`): ``scenario`` (the episode's
    scenario), ``mission``, ``coverage`` (:class:`CoverageGrid`), ``targets_ned`` ((T, 3)
    true target positions, NED m).

    Raises:
        ValueError: inconsistent options (decision interval not a multiple of the autonomy
            period, area not larger than the sonar's reach), or a scenario without an FLS
            entry ``sensors.fls`` (:func:`require_fls`).
        scenarios.load.ScenarioError: a bad scenario or override.
    """

    def __init__(self, scenario: str | Path | Scenario = "cssn_lawnmower",
                 options: SurveyEnvOptions | dict | None = None, overrides: tuple[str, ...] = ()) -> None:
        self.options = opts = _options(options)
        over = list(overrides)
        if opts.physics_rate_hz is not None:
            over.append(f"physics.rate_hz={opts.physics_rate_hz}")
        base = resolve_scenario(scenario, over)
        require_fls(base)
        if not opts.sonar:
            base = resolve_scenario(base, ["sensors.fls.enabled=false"])
        self.base_scenario = base
        self.layout: SurveyLayout = make_layout(base, opts.area_size_ne_m, opts.area_margin_m,
                                                start_clearance_m=opts.start_clearance_m,
                                                min_spacing_m=opts.min_target_spacing_m)
        self.area: OperatingArea = self.layout.area
        self._seabed = episode_seabed(base, self.layout)
        self._latest_fls = _LatestFls()
        self._build(episode_scenario(base, self.layout, self._seabed, np.random.default_rng(0)))
        scn = self.scenario
        self.ticks_per_step = int(round(opts.decision_interval_s / self.mission.autonomy_dt_s))
        if self.ticks_per_step < 1 or abs(self.ticks_per_step * self.mission.autonomy_dt_s
                                          - opts.decision_interval_s) > 1e-6:
            raise ValueError(f"SurveyEnvOptions.decision_interval_s={opts.decision_interval_s} must be a multiple of "
                             f"the autonomy period {self.mission.autonomy_dt_s} s")
        self.decision_interval_s = self.ticks_per_step * self.mission.autonomy_dt_s
        self.max_episode_s = float(scn.duration_s if opts.max_episode_s is None else opts.max_episode_s)
        self.max_yaw_rate_radps = math.radians(scn.autonomy.control.max_yaw_rate_dps)
        self.origin_ned = np.array([*self.area.center_ne_m, 0.0])

        k = opts.top_k_anchors
        a_lo, a_hi = anchor_bounds(k)
        self.obs_fields: dict[str, ObsField] = {
            "nav": ObsField((len(NAV_FEATURES),), np.float32, _NAV_LO, _NAV_HI),
            "anchors": ObsField(a_lo.shape, np.float32, a_lo, a_hi),
            "anchor_mask": ObsField((k,), np.int8, 0, 1),
            "coverage": ObsField(tuple(opts.coverage_shape), np.float32, 0.0, 1.0),
        }
        if opts.sonar:
            self.obs_fields["sonar"] = ObsField(tuple(opts.sonar_shape), np.uint8, 0, 255)
        self.n_act = 3
        self._n_steps = 0
        self._heading_sp_rad = 0.0

    # ------------------------------------------------------------------ state views
    @property
    def t_s(self) -> float:
        """Time since the episode's start, s: the decision clock, decisions x
        ``decision_interval_s``."""
        return self._n_steps * self.decision_interval_s

    @property
    def sim_physics(self) -> Physics:
        """The simulation this task advances now, the episode's mission's
        (``mission.physics``): its MuJoCo ``model`` / ``data`` are what the dm_control
        physics :class:`sim.envs.dm_physics.AuvPhysics` wraps. A new object every episode
        (:meth:`reset` builds the episode's mission)."""
        return self.mission.physics

    @property
    def time_limit_steps(self) -> int:
        """The decision at which an episode is truncated (``max_episode_s`` reached,
        :func:`sim.envs.time_limit.reached_time_limit`)."""
        return time_limit_steps(self.decision_interval_s, self.max_episode_s)

    @property
    def seabed(self) -> Seabed:
        """The episodes' seabed (enlarged to the area plus the sonar's range; same every episode)."""
        return self._seabed

    @property
    def nav(self) -> NavEstimate:
        """The latest navigation estimate (what the observation is built from)."""
        return self._nav

    @property
    def heading_setpoint_rad(self) -> float:
        """Heading the autopilot tracks, rad (NED yaw; the yaw-rate action integrates it)."""
        return self._heading_sp_rad

    # ------------------------------------------------------------------ episode
    def _build(self, scn: Scenario) -> None:
        """Mission, coverage grid and target list of one episode's scenario."""
        opts = self.options
        self.scenario = scn
        self.mission = Mission(scn, nav_source=opts.nav_source, observers=(self._latest_fls,), perception=opts.sonar)
        fls_cfg = scn.sensors.fls
        g = resolve_geometry(fls_cfg)
        mount = Mount.from_config("fls", fls_cfg, self.mission.physics.site_pos_body)
        self.coverage = CoverageGrid(self.area, opts.coverage_shape, self._seabed.depth_at, mount.pos_body_m,
                                     (mount.rpy_rad[0], math.radians(fls_cfg.tilt_deg), mount.rpy_rad[2]),
                                     range_min_m=g.window_near_m, range_max_m=g.window_far_m, fov_rad=g.fov_rad,
                                     vertical_fov_rad=g.vertical_beamwidth_rad,
                                     samples_per_side=opts.coverage_samples_per_side,
                                     min_seen_fraction=opts.coverage_min_seen_fraction)
        self.targets_ned = np.array([t.pos_ned for t in scn.world.targets if t.is_target], dtype=float).reshape(-1, 3)
        self._found = np.zeros(len(self.targets_ned), dtype=bool)

    def reset(self, rng: np.random.Generator) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Start an episode drawn from ``rng`` (object layout, then the mission's seed).

        Returns:
            ``(observation, info)``; info as :meth:`step`'s, without ``energy`` and ``complete``.
        """
        self._build(episode_scenario(self.base_scenario, self.layout, self._seabed, rng))
        mission_seed = int(rng.integers(0, 2**63 - 1))
        rec = self.mission.reset(mission_seed)
        self._rec = rec
        self._nav = rec.nav
        self._heading_sp_rad = float(rec.nav.rpy_rad[2])
        self._n_steps = 0
        self._hold(np.zeros(3))
        self._collided, self._effort, self._new_cells = False, 0.0, 0
        self.coverage.reset()
        self.coverage.observe(rec.nav.pos_ned, rec.nav.rpy_rad)
        self._found[:] = False
        return self._observation(), self._info(False, False, 0)

    def step(self, action: np.ndarray) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]:
        """Hold ``action`` (shape ``(3,)``, clipped to [-1, 1]) for one decision interval:
        :meth:`begin_step`, :meth:`advance`, :meth:`end_step`, the phases the dm_control
        task (:mod:`sim.envs.dm`) calls in the same order.

        Returns:
            ``(observation, reward, terminated, truncated, info)``: terminated when the
            mission completes (coverage reaches ``complete_coverage_fraction``, or every
            target is found with sonar), on a collision, or on leaving the area
            (``area_margin_m`` past it); truncated at ``max_episode_s`` (decision
            :attr:`time_limit_steps`). The hull cannot leave the water
            (:class:`sim.envs.waypoint_task.WaypointTask`). info: ``t_s``, ``coverage_fraction``,
            ``targets_found``, ``new_targets``, ``collision``, ``left_area``,
            ``nav_pos_ned`` (3,) NED m, ``energy`` (integral of the mean squared normalised
            thruster command, s), ``complete``.

        Raises:
            ValueError: an action of another shape, or with NaN or an infinity.
        """
        self.begin_step(action)
        self.advance()
        return self.end_step()

    def begin_step(self, action: np.ndarray) -> None:
        """Phase 1 of :meth:`step`: check and clip ``action`` (shape ``(3,)``, to [-1, 1]),
        hold its setpoint (surge speed m/s, yaw rate, altitude m) and zero the step's
        collision flag, energy and newly covered cells.

        Raises:
            ValueError: an action of another shape, or with NaN or an infinity (nothing is changed then).
        """
        a = checked_action(action, 3, "SurveyTask.step")
        self._hold(a)
        self._collided = False
        self._effort = 0.0
        self._new_cells = 0

    def _hold(self, a: np.ndarray) -> None:
        """The setpoint that :meth:`advance` holds for action ``a`` (clipped, finite)."""
        opts = self.options
        s_lo, s_hi = opts.speed_range_mps
        h_lo, h_hi = opts.altitude_range_m
        speed = s_lo + 0.5 * (a[0] + 1.0) * (s_hi - s_lo)
        altitude = h_lo + 0.5 * (a[2] + 1.0) * (h_hi - h_lo)
        self._yaw_step = a[1] * self.max_yaw_rate_radps * self.mission.autonomy_dt_s
        self._speed, self._altitude = float(speed), float(altitude)

    def advance(self) -> None:
        """Phase 2 of :meth:`step`: one decision interval of the closed-loop mission
        (``ticks_per_step`` autonomy ticks of :meth:`sim.mission.Mission.step`: physics with
        thrusters and Fossen wrench, sensors, navigation filter, with sonar the FLS and
        perception, autopilots), holding the setpoint of the latest :meth:`begin_step`
        (action zeros after :meth:`reset`), the heading setpoint integrating the yaw rate
        tick by tick. Marks the coverage swept at the navigation poses, advances the
        decision clock :attr:`t_s` by ``decision_interval_s``, accumulates contact and
        energy for :meth:`end_step`."""
        m = self.mission
        dt = m.autonomy_dt_s
        collided = self._collided
        n_ticks = self.ticks_per_step
        poses = np.empty((n_ticks, 2, 3))  # per tick: navigation position (NED m) and attitude (rad)
        cmds = np.empty((n_ticks, len(m.thruster_cmd)))
        yaw_step = self._yaw_step
        speed, altitude = self._speed, self._altitude
        for k in range(n_ticks):
            self._heading_sp_rad = float(wrap_angle(self._heading_sp_rad + yaw_step))
            rec = m.step(Setpoint(speed, self._heading_sp_rad, altitude_m=altitude))
            cmds[k] = rec.thruster_cmd
            poses[k, 0] = rec.nav.pos_ned
            poses[k, 1] = rec.nav.rpy_rad
            if m.physics.data.ncon and m.physics.vehicle_in_contact():
                collided = True
        effort = self._effort  # integral of mean(cmd^2), summed tick by tick
        for sq in np.mean(np.square(cmds), axis=1).tolist():
            effort += sq * dt
        self._new_cells += self.coverage.observe_many(poses[:, 0], poses[:, 1])
        self._collided = collided
        self._effort = effort
        self._rec = rec
        self._nav = rec.nav
        self._n_steps += 1

    def end_step(self) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]:
        """Phase 3 of :meth:`step`: targets found, reward, termination, observation and info
        of the decision intervals advanced since :meth:`begin_step` (one in :meth:`step`).

        Returns:
            as :meth:`step`.
        """
        opts, w, m = self.options, self.options.reward, self.mission
        collided, effort, n_new_cells = self._collided, self._effort, self._new_cells
        n_new_targets = 0
        if m.perception is not None:
            n_new_targets = match_new_targets(m.perception.pmha.world_model(), self.targets_ned, self._found,
                                              opts.match_radius_m)
        reward = (w.target * n_new_targets + w.coverage * n_new_cells / self.coverage.covered.size
                  - w.energy_per_s * effort)
        pos = self._rec.truth.pos_ned
        left = bool(not self.area.contains(pos) or pos[2] < 0.0)
        complete = self.coverage.fraction >= opts.complete_coverage_fraction or (
            m.perception is not None and len(self._found) > 0 and bool(np.all(self._found)))
        if collided:
            reward -= w.collision
        if left:
            reward -= w.leave_area
        if complete and not (collided or left):
            reward += w.complete
        terminated = complete or collided or left
        truncated = (not terminated) and reached_time_limit(self._n_steps, self.decision_interval_s,
                                                            self.max_episode_s)
        info = self._info(collided, left, n_new_targets)
        info.update(energy=effort, complete=complete)
        return self._observation(), float(reward), terminated, truncated, info

    # ------------------------------------------------------------------ observation
    def _observation(self) -> dict[str, np.ndarray]:
        nav = self._nav
        m = self.mission
        cov = np.asarray(nav.cov_pos_ned, dtype=float)
        alt = float(nav.altitude_m)
        alt_ok = math.isfinite(alt)
        yaw = float(nav.rpy_rad[2])
        t_frac = min(self._n_steps * self.decision_interval_s / self.max_episode_s, 1.0)
        vec = np.array([nav.pos_ned[0] - self.origin_ned[0], nav.pos_ned[1] - self.origin_ned[1], nav.pos_ned[2],
                        alt if alt_ok else 0.0, float(alt_ok), nav.rpy_rad[0], nav.rpy_rad[1], math.sin(yaw),
                        math.cos(yaw), *nav.vel_body_mps, nav.rate_body_radps[2],
                        math.sqrt(max(cov[0, 0] + cov[1, 1], 0.0)), t_frac, self.coverage.fraction],
                       dtype=np.float64)
        objects = m.perception.pmha.world_model() if m.perception is not None else []
        anchors, mask = anchor_table(objects, self.options.top_k_anchors, self.origin_ned)
        obs = {
            "nav": np.clip(np.nan_to_num(vec), _NAV_LO, _NAV_HI).astype(np.float32),
            "anchors": anchors,
            "anchor_mask": mask,
            "coverage": self.coverage.as_image(),
        }
        if self.options.sonar:
            h, w = self.options.sonar_shape
            fan = self._latest_fls.fan
            obs["sonar"] = (np.zeros((h, w), dtype=np.uint8) if fan is None
                            else cv2.resize(fan, (w, h), interpolation=cv2.INTER_AREA))
        return obs

    def _info(self, collided: bool, left: bool, n_new_targets: int) -> dict[str, Any]:
        return {"t_s": self._n_steps * self.decision_interval_s, "coverage_fraction": self.coverage.fraction,
                "targets_found": int(np.count_nonzero(self._found)), "new_targets": n_new_targets,
                "collision": collided, "left_area": left, "nav_pos_ned": np.asarray(self._nav.pos_ned).copy()}
