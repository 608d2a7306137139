"""``auvsim/Survey-v1``: the Survey task (:mod:`sim.envs.survey_task`) as a gymnasium env.

The task logic lives in :class:`sim.envs.survey_task.SurveyTask`, shared with the dm_control
environment (:mod:`sim.envs.dm`); this module only maps it onto gymnasium's API and spaces.
Each episode draws from the env's generator (``reset(seed=...)``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from autonomy.messages import NavEstimate
from scenarios.schema import Scenario
from sim.envs.coverage import CoverageGrid
from sim.envs.survey_task import NAV_FEATURES, SurveyEnvOptions, SurveyRewardWeights, SurveyTask
from sim.mission import Mission
from sim.scene.seabed import Seabed

__all__ = ["NAV_FEATURES", "SurveyEnv", "SurveyEnvOptions", "SurveyRewardWeights", "SurveyTask", "refuse_reset_options"]


def refuse_reset_options(options: dict | None) -> None:
    """Raise ValueError for reset options: the Survey env takes its options when it is made."""
    if options:
        raise ValueError(f"options: the Survey env's reset takes none (set them when making the env), got {options!r}")


class SurveyEnv(gym.Env):
    """Survey an area for targets; observation and action as :class:`SurveyTask` documents
    them: action ``Box([-1, 1]^3)``, observation ``Dict`` of ``Box`` es (``anchor_mask`` a
    ``MultiBinary``; ``sonar`` only with sonar on).

    Attributes:
        task: the shared task object.
        options, base_scenario, layout, area, decision_interval_s, ticks_per_step,
        max_episode_s, max_yaw_rate_radps, origin_ned: the task's (fixed).
        scenario, mission, coverage, targets_ned, nav, heading_setpoint_rad, seabed: the
            task's, read through (they change per episode / step).

    Raises:
        ValueError, scenarios.load.ScenarioError: as :class:`SurveyTask`.
    """

    metadata = {"render_modes": []}

    def __init__(self, scenario: str | Path | Scenario = "cssn_lawnmower",
                 options: SurveyEnvOptions | dict | None = None, overrides: tuple[str, ...] = ()) -> None:
        self.task = task = SurveyTask(scenario, options, overrides)
        self.options, self.base_scenario = task.options, task.base_scenario
        self.layout, self.area = task.layout, task.area
        self.decision_interval_s, self.ticks_per_step = task.decision_interval_s, task.ticks_per_step
        self.max_episode_s, self.max_yaw_rate_radps = task.max_episode_s, task.max_yaw_rate_radps
        self.origin_ned = task.origin_ned
        obs_spaces: dict[str, spaces.Space] = {
            key: (spaces.MultiBinary(f.shape) if key == "anchor_mask"
                  else spaces.Box(f.low, f.high, f.shape, dtype=f.dtype))
            for key, f in task.obs_fields.items()
        }
        self.observation_space = spaces.Dict(obs_spaces)
        self.action_space = spaces.Box(-1.0, 1.0, (task.n_act,), dtype=np.float32)

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[dict, dict[str, Any]]:
        refuse_reset_options(options)
        super().reset(seed=seed)
        return self.task.reset(self.np_random)

    def step(self, action: np.ndarray) -> tuple[dict, float, bool, bool, dict[str, Any]]:
        return self.task.step(action)

    # ------------------------------------------------------------------ per-episode views
    @property
    def scenario(self) -> Scenario:
        """The current episode's scenario (the base one with the drawn layout)."""
        return self.task.scenario

    @property
    def mission(self) -> Mission:
        """The current episode's closed-loop mission."""
        return self.task.mission

    @property
    def coverage(self) -> CoverageGrid:
        """The current episode's coverage grid."""
        return self.task.coverage

    @property
    def targets_ned(self) -> np.ndarray:
        """(T, 3) the current episode's true target positions, NED m."""
        return self.task.targets_ned

    @property
    def nav(self) -> NavEstimate:
        """The latest navigation estimate."""
        return self.task.nav

    @property
    def heading_setpoint_rad(self) -> float:
        """Heading the autopilot tracks, rad (NED yaw)."""
        return self.task.heading_setpoint_rad

    @property
    def seabed(self) -> Seabed:
        """The episodes' seabed."""
        return self.task.seabed
