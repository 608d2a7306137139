"""The auvsim tasks as dm_control environments ([dmcontrol2020]), for dm_env based agents
(Acme and others).

Built the way dm_control's own suite builds its tasks (``dm_control/suite/cartpole.py``):
a ``dm_control.rl.control.Environment`` of a physics, :class:`sim.envs.dm_physics.AuvPhysics`
(a ``dm_control.mujoco.Physics`` wrapping the simulation's own ``MjModel`` / ``MjData``),
and a ``dm_control.rl.control.Task`` per environment, :class:`WaypointControlTask` and
:class:`SurveyControlTask`. ``load("auvsim/Waypoint-v1", seed=0)`` builds the Waypoint task
(:class:`sim.envs.waypoint_task.WaypointTask`) and ``load("auvsim/Survey-v1", seed=0)`` the
Survey task (:class:`sim.envs.survey_task.SurveyTask`), the same task classes the
gymnasium envs use.

One step, in ``control.Environment.step``'s order, runs the shared task's phases as the
gymnasium env's ``task.step`` does: ``before_step`` -> ``begin_step(action)`` (check,
clip, hold the command), ``physics.step(1)`` -> ``advance()`` (one decision interval of
the auvsim loop: thrusters, Fossen hydrodynamics, MuJoCo at the physics rate; Survey: the
whole mission with sensors, navigation and, with sonar, perception), ``after_step`` ->
``end_step()`` (reward, termination, observation, info), which ``get_reward``,
``get_observation`` and ``get_termination`` then return. In dm_control's time one control
step is one decision interval: ``physics.timestep()`` and ``env.control_timestep()`` are
the task's ``decision_interval_s`` (one physics step per control step).

Seeding: with the same seed and actions the two interfaces give the same trajectory, bit
for bit: gymnasium's ``reset(seed=s)`` and this env's ``seed=s`` seed one
``numpy.random.Generator(PCG64(SeedSequence(s)))`` (:func:`episode_generator`), and each
later episode continues it. The task draws from that generator (``task.rng``), not from a
``numpy.random.RandomState`` as ``dm_control.suite.base.Task(random=...)`` would.

Episode ends: a terminal step (Waypoint: every waypoint reached; Survey: the mission
complete; both: collision, leaving the area; the hull cannot leave the water,
:class:`sim.envs.waypoint_task.WaypointTask`) is a ``LAST`` step with discount 0
(``get_termination`` returns 0.0); the time limit (``max_episode_s``) is
``control.Environment``'s ``time_limit``, a ``LAST`` step with discount 1 (a truncation) at
the decision where the gymnasium env reports ``truncated`` (``task.time_limit_steps``). A
terminal step on that same decision keeps discount 0, as gymnasium's ``terminated``
(``control.Environment`` alone would give the time limit's 1). ``step`` after a ``LAST``
step (or on a fresh env) starts a new episode, as dm_env specifies.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import dm_env
import numpy as np
from dm_control.rl import control
from dm_env import specs

from scenarios.schema import Scenario
from sim.envs.dm_physics import AuvPhysics
from sim.envs.registration import SURVEY_ID, WAYPOINT_ID
from sim.envs.survey_task import SurveyEnvOptions, SurveyTask
from sim.envs.waypoint_task import WaypointEnvOptions, WaypointTask

__all__ = ["AuvEnvironment", "AuvPhysics", "AuvTask", "DM_ENV_IDS", "SurveyControlTask", "SurveyDmEnv",
           "WaypointControlTask", "WaypointDmEnv", "episode_generator", "load"]


def episode_generator(seed: int | np.random.Generator | None) -> np.random.Generator:
    """The episode generator for ``seed``: the one gymnasium's ``reset(seed=seed)`` builds
    (``Generator(PCG64(SeedSequence(seed)))``; fresh entropy for None); a Generator is used as is.

    Raises:
        ValueError: a seed that is not a non-negative integer, a Generator or None.
    """
    if isinstance(seed, np.random.Generator):
        return seed
    if seed is not None and (not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0):
        raise ValueError(f"seed must be a non-negative integer, a numpy Generator or None, got {seed!r}")
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(None if seed is None else int(seed))))


class AuvTask(control.Task):
    """A ``dm_control.rl.control.Task`` over a shared auvsim task (``reset(rng)``,
    ``begin_step``, ``advance``, ``end_step``): the hooks call its phases, the getters
    return what its ``end_step`` (or ``reset``) gave.

    Args:
        shared: the shared task object.
        seed: root of the episodes' draws (int >= 0, a ``numpy.random.Generator``, or None
            for fresh entropy); see :func:`episode_generator`.

    Attributes:
        shared: the shared task. Attributes this class does not define are read from it
            (``task.options``, ``task.mission``, ``task.targets_ned``, ...).
        rng: the episode generator (a ``numpy.random.Generator``; dm_control's
            ``RandomState`` convention is not used).
        last_info: the shared task's info dict of the latest reset / step.
        terminated, truncated: the shared task's flags of the latest step (False after a
            reset).

    Raises:
        ValueError: a bad seed.
    """

    def __init__(self, shared: Any, seed: int | np.random.Generator | None = None) -> None:
        self.shared = shared
        self.rng = episode_generator(seed)
        self.last_info: dict[str, Any] = {}
        self._obs: Any = None
        self._reward = 0.0
        self.terminated = False
        self.truncated = False
        self._act_spec = specs.BoundedArray((shared.n_act,), np.float32, -1.0, 1.0, name="action")

    def __getattr__(self, name: str) -> Any:
        if name == "shared" or name.startswith("__"):
            raise AttributeError(name)
        return getattr(self.shared, name)

    # ------------------------------------------------------------------ episode
    def initialize_episode(self, physics: AuvPhysics) -> None:
        """Draw and start an episode from :attr:`rng` (the shared task's ``reset``); the
        physics then wraps the episode's simulation (:meth:`AuvPhysics.bind`)."""
        self._obs, self.last_info = self.shared.reset(self.rng)
        self._reward, self.terminated, self.truncated = 0.0, False, False
        physics.bind()

    def before_step(self, action: np.ndarray, physics: AuvPhysics) -> None:
        """The shared task's ``begin_step(action)``.

        Raises:
            ValueError: an action of another shape, or with NaN or an infinity.
        """
        self.shared.begin_step(action)

    def after_step(self, physics: AuvPhysics) -> None:
        """The shared task's ``end_step()``: its observation, reward, flags and info are kept
        for the getters."""
        (self._obs, self._reward, self.terminated, self.truncated,
         self.last_info) = self.shared.end_step()

    def get_observation(self, physics: AuvPhysics) -> Any:
        return self._obs

    def get_reward(self, physics: AuvPhysics) -> float:
        return self._reward

    def get_termination(self, physics: AuvPhysics) -> float | None:
        """0.0 on a terminal step, else None (the time limit is the environment's)."""
        return 0.0 if self.terminated else None

    def action_spec(self, physics: AuvPhysics) -> specs.BoundedArray:
        """float32 ``(n_act,)`` in [-1, 1] (values outside are clipped)."""
        return self._act_spec


class WaypointControlTask(AuvTask):
    """``auvsim/Waypoint-v1`` as a ``control.Task`` over a :class:`WaypointTask`.

    Observation: float32 array, shape ``(shared.obs_size,)``, bounded as
    :class:`WaypointTask` documents (one array, not dm_control's dict: the spec is one
    ``BoundedArray`` named ``observation``). Action: float32 ``(n_act,)`` in [-1, 1].
    """

    def __init__(self, shared: WaypointTask, seed: int | np.random.Generator | None = None) -> None:
        super().__init__(shared, seed)
        self._obs_spec = specs.BoundedArray((shared.obs_size,), np.float32, shared.obs_low, shared.obs_high,
                                            name="observation")

    def observation_spec(self, physics: AuvPhysics) -> specs.BoundedArray:
        return self._obs_spec


class SurveyControlTask(AuvTask):
    """``auvsim/Survey-v1`` as a ``control.Task`` over a :class:`SurveyTask`.

    Observation: a dict of arrays, one ``BoundedArray`` spec per field of
    :attr:`SurveyTask.obs_fields` (see :class:`SurveyDmEnv`). Action: float32 ``(3,)`` in
    [-1, 1].
    """

    def __init__(self, shared: SurveyTask, seed: int | np.random.Generator | None = None) -> None:
        super().__init__(shared, seed)
        self._obs_spec = {
            key: specs.BoundedArray(f.shape, f.dtype, np.broadcast_to(np.asarray(f.low, f.dtype), f.shape),
                                    np.broadcast_to(np.asarray(f.high, f.dtype), f.shape), name=key)
            for key, f in shared.obs_fields.items()
        }

    def observation_spec(self, physics: AuvPhysics) -> dict[str, specs.BoundedArray]:
        return dict(self._obs_spec)


def _time_limit_s(n_steps: int, control_timestep_s: float) -> float:
    """The ``time_limit`` for which ``control.Environment`` (step limit ``time_limit /
    control_timestep``, reached when the step count is at least that) ends the episode at
    step ``n_steps`` exactly: ``n_steps * control_timestep_s``, lowered by ulps while
    rounding puts the quotient above ``n_steps``."""
    limit = n_steps * control_timestep_s
    while limit / control_timestep_s > n_steps:
        limit = float(np.nextafter(limit, 0.0))
    return limit


class AuvEnvironment(control.Environment):
    """A ``dm_control.rl.control.Environment`` of an :class:`AuvTask` and the
    :class:`AuvPhysics` of its shared task: ``control_timestep`` = the decision interval,
    ``time_limit`` = ``max_episode_s`` rounded to the decision at which the task truncates
    (``task.time_limit_steps``), observations as the task gives them (not flattened).

    Args:
        task: the dm_control task.

    Attributes:
        task, physics: dm_control's (``env.task.shared`` is the shared task).
        time_limit_steps: the decision at which episodes are truncated.
        last_info: the shared task's info dict of the latest ``reset`` / ``step``.

    Raises:
        RuntimeError: dm_control's step limit would not end episodes at
            ``time_limit_steps`` (construction), or disagrees with the task's truncation
            (``step``); neither happens by construction.
    """

    def __init__(self, task: AuvTask) -> None:
        physics = AuvPhysics(task.shared)
        dt = physics.timestep()
        self.time_limit_steps = int(task.shared.time_limit_steps)
        super().__init__(physics, task, time_limit=_time_limit_s(self.time_limit_steps, dt), control_timestep=dt)
        if self._n_sub_steps != 1 or not self.time_limit_steps - 1 < self._step_limit <= self.time_limit_steps:
            raise RuntimeError(f"control.Environment step limit {self._step_limit} (sub-steps {self._n_sub_steps}) "
                               f"does not end episodes at decision {self.time_limit_steps}")

    @property
    def last_info(self) -> dict[str, Any]:
        return self._task.last_info

    def step(self, action: np.ndarray) -> dm_env.TimeStep:
        """``control.Environment.step``; a terminal step on the time limit's decision keeps
        discount 0 (the task's termination wins, as gymnasium's ``terminated``).

        Raises:
            ValueError: an action of another shape, or with NaN or an infinity.
            dm_control.rl.control.PhysicsError: MuJoCo raised a warning during the step.
        """
        ts = super().step(action)
        if ts.step_type is not dm_env.StepType.FIRST:
            if self._task.terminated:
                if ts.discount != 0.0:
                    ts = ts._replace(discount=0.0)
            elif self._task.truncated != ts.last():  # never, by construction of time_limit
                raise RuntimeError(f"step {self._step_count}: the task's truncated={self._task.truncated} disagrees "
                                   f"with the environment's step limit {self._step_limit}")
        return ts


class WaypointDmEnv(AuvEnvironment):
    """``auvsim/Waypoint-v1`` as a ``dm_control.rl.control.Environment``.

    Observation: float32 array, shape ``(task.obs_size,)``, bounded as
    :class:`WaypointTask` documents. Action: float32 array, shape ``(task.n_act,)``, in
    [-1, 1] (values outside are clipped). Reward: float64 scalar. Discount: 1, or 0 on a
    terminal step. One step: one decision interval (``options.decision_interval_s``).

    Args:
        scenario, options, overrides: as :class:`WaypointTask`.
        seed: root of the episodes' draws (int >= 0, a ``numpy.random.Generator``, or None
            for fresh entropy).

    Attributes:
        task: the :class:`WaypointControlTask` (the shared :class:`WaypointTask` is
            ``task.shared``, its attributes read through: ``task.options``, ...).
        physics: the :class:`AuvPhysics` (``physics.pos_ned()``, ``physics.named.data.qpos``).
        last_info: the task's info dict of the latest ``reset`` / ``step`` (time, waypoints
            reached, distance, collision, position NED m, energy).

    Raises:
        ValueError: a bad seed, bad options or a non-finite action (``step``).
        scenarios.load.ScenarioError: a bad scenario or override.
    """

    def __init__(self, scenario: str | Path | Scenario = "cssn_lawnmower",
                 options: WaypointEnvOptions | dict | None = None, overrides: tuple[str, ...] = (),
                 seed: int | np.random.Generator | None = None) -> None:
        rng = episode_generator(seed)
        super().__init__(WaypointControlTask(WaypointTask(scenario, options, overrides), rng))


class SurveyDmEnv(AuvEnvironment):
    """``auvsim/Survey-v1`` as a ``dm_control.rl.control.Environment``.

    Observation: a dict of arrays, one ``BoundedArray`` spec per field of
    :attr:`SurveyTask.obs_fields`: ``nav`` float32 ``(16,)``, ``anchors`` float32
    ``(top_k_anchors, len(ANCHOR_FEATURES))``, ``anchor_mask`` int8 ``(top_k_anchors,)`` in
    {0, 1}, ``coverage`` float32 ``coverage_shape`` in {0, 1} and, with ``sonar=True``,
    ``sonar`` uint8 ``sonar_shape`` (units and frames as :class:`SurveyTask` documents).
    Action: float32 array, shape ``(3,)``, in [-1, 1] (surge speed, yaw rate, altitude;
    values outside are clipped). Reward: float64 scalar. Discount: 1, or 0 on a terminal
    step. One step: one decision interval (``options.decision_interval_s``).

    Args:
        scenario, options, overrides: as :class:`SurveyTask`.
        seed: root of the episodes' draws (int >= 0, a ``numpy.random.Generator``, or None
            for fresh entropy).

    Attributes:
        task: the :class:`SurveyControlTask` (the shared :class:`SurveyTask` is
            ``task.shared``, its attributes read through: ``task.mission``,
            ``task.targets_ned``, ...).
        physics: the :class:`AuvPhysics`, wrapping each episode's mission physics.
        last_info: the task's info dict of the latest ``reset`` / ``step`` (time, coverage
            fraction, targets found, collision, navigation position NED m, energy, complete).

    Raises:
        ValueError: a bad seed, bad options or a non-finite action (``step``).
        scenarios.load.ScenarioError: a bad scenario or override.
    """

    def __init__(self, scenario: str | Path | Scenario = "cssn_lawnmower",
                 options: SurveyEnvOptions | dict | None = None, overrides: tuple[str, ...] = (),
                 seed: int | np.random.Generator | None = None) -> None:
        rng = episode_generator(seed)
        super().__init__(SurveyControlTask(SurveyTask(scenario, options, overrides), rng))


DM_ENV_IDS = {SURVEY_ID: SurveyDmEnv, WAYPOINT_ID: WaypointDmEnv}


def load(env_id: str, **kwargs: Any) -> AuvEnvironment:
    """Build the dm_control environment of ``env_id`` (``auvsim/Survey-v1`` or
    ``auvsim/Waypoint-v1``) with the env class's keyword arguments (``scenario``,
    ``options``, ``overrides``, ``seed``).

    Raises:
        ValueError: an id without a dm_env version (the message lists those there are).
    """
    if env_id not in DM_ENV_IDS:
        raise ValueError(f"no dm_env version of {env_id!r}; available: {sorted(DM_ENV_IDS)}")
    return DM_ENV_IDS[env_id](**kwargs)
