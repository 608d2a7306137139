"""The auvsim tasks as ``dm_env.Environment`` s, for dm_env based agents (Acme and others).

``load("auvsim/Waypoint-v1", seed=0)`` builds the Waypoint task
(:class:`sim.envs.waypoint_task.WaypointTask`) and ``load("auvsim/Survey-v1", seed=0)`` the
Survey task (:class:`sim.envs.survey_task.SurveyTask`), the same objects the gymnasium envs
wrap, behind dm_env's API. With the same seed and actions the two interfaces give the same
trajectory, bit for bit: ``gymnasium``'s ``reset(seed=s)`` and this env's ``seed=s`` seed one
``numpy.random.Generator(PCG64(SeedSequence(s)))``, and each later episode continues it.

Episode ends: a terminal step (Waypoint: every waypoint reached; Survey: the mission
complete; both: collision, leaving the area; the hull cannot leave the water,
:class:`sim.envs.waypoint_task.WaypointTask`) is a ``LAST`` step with discount
0; the time limit (``max_episode_s``) is a ``LAST`` step with discount 1 (a truncation).
``step`` after a ``LAST`` step (or on a fresh env) starts a new episode, as dm_env
specifies.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import dm_env
import numpy as np
from dm_env import specs

from scenarios.schema import Scenario
from sim.envs.registration import SURVEY_ID, WAYPOINT_ID
from sim.envs.survey_task import SurveyEnvOptions, SurveyTask
from sim.envs.waypoint_task import WaypointEnvOptions, WaypointTask

__all__ = ["SurveyDmEnv", "WaypointDmEnv", "load", "DM_ENV_IDS"]


def episode_generator(seed: int | np.random.Generator | None) -> np.random.Generator:
    """The episode generator for ``seed``: the one gymnasium's ``reset(seed=seed)`` builds
    (``Generator(PCG64(SeedSequence(seed)))``; fresh entropy for None); a Generator is used as is."""
    if isinstance(seed, np.random.Generator):
        return seed
    if seed is not None and (not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0):
        raise ValueError(f"seed must be a non-negative integer, a numpy Generator or None, got {seed!r}")
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(None if seed is None else int(seed))))


class _TaskDmEnv(dm_env.Environment):
    """dm_env's API over a task object with ``reset(rng) -> (obs, info)`` and
    ``step(action) -> (obs, reward, terminated, truncated, info)``: the step-type and
    discount bookkeeping shared by the auvsim dm_env envs."""

    task: Any

    def __init__(self, seed: int | np.random.Generator | None) -> None:
        self._rng = episode_generator(seed)
        self.last_info: dict[str, Any] = {}
        self._needs_reset = True

    def reset(self) -> dm_env.TimeStep:
        obs, self.last_info = self.task.reset(self._rng)
        self._needs_reset = False
        return dm_env.restart(obs)

    def step(self, action: np.ndarray) -> dm_env.TimeStep:
        if self._needs_reset:
            return self.reset()
        obs, reward, terminated, truncated, self.last_info = self.task.step(action)
        if terminated:
            self._needs_reset = True
            return dm_env.termination(reward, obs)
        if truncated:
            self._needs_reset = True
            return dm_env.truncation(reward, obs)
        return dm_env.transition(reward, obs)

    def reward_spec(self) -> specs.Array:
        return specs.Array((), np.float64, name="reward")

    def discount_spec(self) -> specs.BoundedArray:
        return specs.BoundedArray((), np.float64, 0.0, 1.0, name="discount")


class WaypointDmEnv(_TaskDmEnv):
    """``auvsim/Waypoint-v1`` as a ``dm_env.Environment``.

    Observation: float32 array, shape ``(task.obs_size,)``, bounded as
    :class:`WaypointTask` documents. Action: float32 array, shape ``(task.n_act,)``, in
    [-1, 1] (values outside are clipped). Reward: float64 scalar. Discount: 1, or 0 on a
    terminal step.

    Args:
        scenario, options, overrides: as :class:`WaypointTask`.
        seed: root of the episodes' draws (int >= 0, a ``numpy.random.Generator``, or None
            for fresh entropy).

    Attributes:
        task: the shared task object.
        last_info: the task's info dict of the latest ``reset`` / ``step`` (time, waypoints
            reached, distance, collision, position NED m, energy).

    Raises:
        ValueError: a bad seed, bad options or a non-finite action (``step``).
        scenarios.load.ScenarioError: a bad scenario or override.
    """

    def __init__(self, scenario: str | Path | Scenario = "cssn_lawnmower",
                 options: WaypointEnvOptions | dict | None = None, overrides: tuple[str, ...] = (),
                 seed: int | np.random.Generator | None = None) -> None:
        super().__init__(seed)
        self.task = WaypointTask(scenario, options, overrides)
        self._obs_spec = specs.BoundedArray((self.task.obs_size,), np.float32, self.task.obs_low,
                                            self.task.obs_high, name="observation")
        self._act_spec = specs.BoundedArray((self.task.n_act,), np.float32, -1.0, 1.0, name="action")

    def observation_spec(self) -> specs.BoundedArray:
        return self._obs_spec

    def action_spec(self) -> specs.BoundedArray:
        return self._act_spec


class SurveyDmEnv(_TaskDmEnv):
    """``auvsim/Survey-v1`` as a ``dm_env.Environment``.

    Observation: a dict of arrays, one ``BoundedArray`` spec per field of
    :attr:`SurveyTask.obs_fields`: ``nav`` float32 ``(16,)``, ``anchors`` float32
    ``(top_k_anchors, len(ANCHOR_FEATURES))``, ``anchor_mask`` int8 ``(top_k_anchors,)`` in
    {0, 1}, ``coverage`` float32 ``coverage_shape`` in {0, 1} and, with ``sonar=True``,
    ``sonar`` uint8 ``sonar_shape`` (units and frames as :class:`SurveyTask` documents).
    Action: float32 array, shape ``(3,)``, in [-1, 1] (surge speed, yaw rate, altitude;
    values outside are clipped). Reward: float64 scalar. Discount: 1, or 0 on a terminal
    step.

    Args:
        scenario, options, overrides: as :class:`SurveyTask`.
        seed: root of the episodes' draws (int >= 0, a ``numpy.random.Generator``, or None
            for fresh entropy).

    Attributes:
        task: the shared task object.
        last_info: the task's info dict of the latest ``reset`` / ``step`` (time, coverage
            fraction, targets found, collision, navigation position NED m, energy, complete).

    Raises:
        ValueError: a bad seed, bad options or a non-finite action (``step``).
        scenarios.load.ScenarioError: a bad scenario or override.
    """

    def __init__(self, scenario: str | Path | Scenario = "cssn_lawnmower",
                 options: SurveyEnvOptions | dict | None = None, overrides: tuple[str, ...] = (),
                 seed: int | np.random.Generator | None = None) -> None:
        super().__init__(seed)
        self.task = SurveyTask(scenario, options, overrides)
        self._obs_spec = {
            key: specs.BoundedArray(f.shape, f.dtype, np.broadcast_to(np.asarray(f.low, f.dtype), f.shape),
                                    np.broadcast_to(np.asarray(f.high, f.dtype), f.shape), name=key)
            for key, f in self.task.obs_fields.items()
        }
        self._act_spec = specs.BoundedArray((self.task.n_act,), np.float32, -1.0, 1.0, name="action")

    def observation_spec(self) -> dict[str, specs.BoundedArray]:
        return dict(self._obs_spec)

    def action_spec(self) -> specs.BoundedArray:
        return self._act_spec


DM_ENV_IDS = {SURVEY_ID: SurveyDmEnv, WAYPOINT_ID: WaypointDmEnv}


def load(env_id: str, **kwargs: Any) -> dm_env.Environment:
    """Build the dm_env version of ``env_id`` (``auvsim/Survey-v1`` or ``auvsim/Waypoint-v1``)
    with the env class's keyword arguments (``scenario``, ``options``, ``overrides``, ``seed``).

    Raises:
        ValueError: an id without a dm_env version (the message lists those there are).
    """
    if env_id not in DM_ENV_IDS:
        raise ValueError(f"no dm_env version of {env_id!r}; available: {sorted(DM_ENV_IDS)}")
    return DM_ENV_IDS[env_id](**kwargs)
