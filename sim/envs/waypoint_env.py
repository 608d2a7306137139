"""``auvsim/Waypoint-v1``: the Waypoint task (:mod:`sim.envs.waypoint_task`) as a gymnasium env.

The task logic lives in :class:`sim.envs.waypoint_task.WaypointTask`, shared with the dm_control
environment (:mod:`sim.envs.dm`); this module only maps it onto gymnasium's API and spaces.
Each episode draws from the env's generator (``reset(seed=...)``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from scenarios.schema import Scenario
from sim.envs.waypoint_task import ACTION_MODES, WaypointEnvOptions, WaypointRewardWeights, WaypointTask

__all__ = ["ACTION_MODES", "WaypointEnv", "WaypointEnvOptions", "WaypointRewardWeights", "WaypointTask"]


class WaypointEnv(gym.Env):
    """Reach waypoints under currents (no sonar); observation and action as
    :class:`WaypointTask` documents them, as ``Box`` spaces.

    Attributes:
        task: the shared task object (state views ``pos_ned``, ``rpy_rad``,
            ``heading_setpoint_rad``, ``waypoint_ned()``).
        options, scenario, area, physics, params, world, dt_s, decision_interval_s, n_act,
        max_yaw_rate_radps: the task's.

    Raises:
        ValueError, scenarios.load.ScenarioError: as :class:`WaypointTask`.
    """

    metadata = {"render_modes": []}

    def __init__(self, scenario: str | Path | Scenario = "cssn_lawnmower",
                 options: WaypointEnvOptions | dict | None = None, overrides: tuple[str, ...] = ()) -> None:
        self.task = task = WaypointTask(scenario, options, overrides)
        self.options, self.scenario, self.area = task.options, task.scenario, task.area
        self.physics, self.params, self.world = task.physics, task.params, task.world
        self.dt_s, self.decision_interval_s, self.n_act = task.dt_s, task.decision_interval_s, task.n_act
        self.max_yaw_rate_radps = task.max_yaw_rate_radps
        self.action_space = spaces.Box(-1.0, 1.0, (task.n_act,), dtype=np.float32)
        self.observation_space = spaces.Box(task.obs_low, task.obs_high, dtype=np.float32)

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        return self.task.reset(self.np_random)

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        return self.task.step(action)

    def waypoint_ned(self) -> np.ndarray:
        """(3,) the waypoint being sought (the last one once all are reached), NED, m."""
        return self.task.waypoint_ned()
