"""The batched Survey env as a Stable-Baselines3 ``VecEnv`` ([Raffin2021]; the ``train`` extra).

Stable-Baselines3 keeps its own vector-env interface (``reset() -> obs``, ``step_async`` /
``step_wait -> (obs, rewards, dones, infos)`` with one info dict per env, the ending step
returning the next episode's first observation and the final one in
``info["terminal_observation"]``, ``info["TimeLimit.truncated"]`` for a time limit).
:class:`Sb3SurveyVecEnv` runs a :class:`sim.envs.survey_vector.SurveyVectorEnv` in
``AutoresetMode.SAME_STEP`` and translates, so PPO, A2C, SAC ... train on it as on their own
vector envs, with its worker processes and shared detector. The sonar image is given a channel
axis, ``(1, H, W)`` uint8, so that Stable-Baselines3 sees an image: its multi-input policy
scales it to [0, 1] and reads it with its CNN (a flat 0-255 vector in an MLP learns poorly).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode
from stable_baselines3.common.vec_env.base_vec_env import VecEnv

from scenarios.schema import Scenario
from sim.envs.survey_task import SurveyEnvOptions, is_int
from sim.envs.survey_vector import SurveyVectorEnv


class Sb3SurveyVecEnv(VecEnv):
    """N Survey envs for Stable-Baselines3.

    Args:
        num_envs, scenario, options, overrides, workers: as :class:`SurveyVectorEnv`.
        seed: root seed; env ``i`` is reset with ``seed + i`` on the first :meth:`reset`
            (None: unseeded), and continues its own generator after that. ``seed(s)`` (what
            ``PPO(..., seed=s)`` calls) seeds the next :meth:`reset` with ``s + i`` the same way.

    At an episode's end the step's info is the ending step's (``terminal_observation`` and
    ``TimeLimit.truncated`` added), the new episode's first info is in ``reset_infos[i]``, as
    Stable-Baselines3's own vector envs do.

    Raises:
        ValueError: ``seed`` not an integer >= 0 or None; as :class:`SurveyVectorEnv`.
    """

    def __init__(self, num_envs: int, scenario: str | Path | Scenario = "cssn_lawnmower",
                 options: SurveyEnvOptions | dict | None = None, overrides: tuple[str, ...] = (), *,
                 workers: int = 1, seed: int | None = None) -> None:
        if seed is not None and (not is_int(seed) or seed < 0):
            raise ValueError(f"seed must be an integer >= 0 or None, got {seed!r}")
        self.venv = SurveyVectorEnv(num_envs, scenario, options, overrides, workers=workers,
                                    autoreset_mode=AutoresetMode.SAME_STEP)
        space = self.venv.single_observation_space
        if "sonar" in space.spaces:
            s = space["sonar"]
            space = spaces.Dict({**space.spaces, "sonar": spaces.Box(0, 255, (1, *s.shape), dtype=np.uint8)})
        super().__init__(num_envs, space, self.venv.single_action_space)
        if seed is not None:
            self.seed(seed)  # the first reset's seeds, as PPO(seed=...) sets them
        self._actions: np.ndarray | None = None

    def reset(self) -> dict[str, np.ndarray]:
        seeded = any(s is not None for s in self._seeds)  # seed(s) before this reset
        obs, infos = self.venv.reset(seed=list(self._seeds) if seeded else None)
        self._reset_seeds()
        self.reset_infos = [self._info(infos, i) for i in range(self.num_envs)]
        return self._image(obs)

    @staticmethod
    def _info(infos: dict[str, Any], i: int) -> dict[str, Any]:
        """Env ``i``'s entries of gymnasium's vector info (the keys its ``_key`` mask marks)."""
        return {k: v[i] for k, v in infos.items()
                if not k.startswith("_") and k not in ("final_obs", "final_info")
                and (f"_{k}" not in infos or infos[f"_{k}"][i])}

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions, dtype=np.float32).reshape(self.num_envs, -1)

    def step_wait(self):
        obs, rewards, terms, truncs, infos = self.venv.step(self._actions)
        dones = terms | truncs
        out: list[dict[str, Any]] = []
        for i in range(self.num_envs):
            info = self._info(infos, i)
            if dones[i]:  # the ending step's info; the new episode's first one goes to reset_infos
                self.reset_infos[i] = info
                info = self._info(infos["final_info"], i)  # gymnasium's vector form, as the step's infos
                final = infos["final_obs"][i]  # gymnasium keeps the final dict observations in an object array
                info["terminal_observation"] = {**final, "sonar": final["sonar"][None]} if "sonar" in final else final
                info["TimeLimit.truncated"] = bool(truncs[i] and not terms[i])
            out.append(info)
        return self._image(obs), rewards.astype(np.float32), dones, out

    @staticmethod
    def _image(obs: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """The batch's sonar images with a channel axis, (N, 1, H, W)."""
        return {**obs, "sonar": obs["sonar"][:, None]} if "sonar" in obs else obs

    def close(self) -> None:
        self.venv.close()

    # the rest of SB3's interface: attributes and methods of the envs, which live in the workers
    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        if attr_name == "render_mode":
            return [None] * len(self._indices(indices))
        raise AttributeError(f"Sb3SurveyVecEnv: {attr_name!r} of the envs is not reachable (they live in the workers)")

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        raise AttributeError(f"Sb3SurveyVecEnv: cannot set {attr_name!r} on the envs")

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs) -> list[Any]:
        raise AttributeError(f"Sb3SurveyVecEnv: cannot call {method_name!r} on the envs")

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [False] * len(self._indices(indices))

    def _indices(self, indices) -> list[int]:
        if indices is None:
            return list(range(self.num_envs))
        return [indices] if isinstance(indices, int) else list(indices)
