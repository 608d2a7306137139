"""``auvsim/Survey-v1`` batched: N Survey envs stepped in lockstep as one gymnasium vector env
(:class:`SurveyVectorEnv`; ``gymnasium.make_vec("auvsim/Survey-v1", num_envs=N,
vectorization_mode="vector_entry_point")`` builds one).
"""

from __future__ import annotations

import multiprocessing as mp
import traceback
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium.error import ClosedEnvironmentError, ResetNeeded
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from scenarios.schema import Scenario
from sim.envs.survey_env import SurveyEnv, refuse_reset_options
from sim.envs.survey_task import SurveyEnvOptions, is_int

Step = tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]


class EnvBlock:
    """A contiguous block of Survey envs stepped in turn, with next-step autoreset (what each
    worker process of :class:`SurveyVectorEnv` holds)."""

    def __init__(self, n: int, scenario: str | Path | Scenario, options: SurveyEnvOptions | dict | None,
                 overrides: tuple[str, ...], same_step: bool = False) -> None:
        self.envs = [SurveyEnv(scenario, options, overrides) for _ in range(n)]
        self.needs_reset = np.zeros(n, dtype=bool)
        self.same_step = same_step

    def reset(self, seeds: list[int | None]) -> list[tuple[dict, dict]]:
        self.needs_reset[:] = False
        return [env.reset(seed=s) for env, s in zip(self.envs, seeds)]

    def step(self, actions: np.ndarray) -> list[Step]:
        out: list[Step] = []
        for i, (env, a) in enumerate(zip(self.envs, actions)):
            if self.needs_reset[i]:
                obs, info = env.reset()
                out.append((obs, 0.0, False, False, info))
                self.needs_reset[i] = False
            else:
                obs, reward, term, trunc, info = env.step(a)
                if self.same_step and (term or trunc):  # gymnasium's SAME_STEP: the final step in the info
                    final = {"final_obs": obs, "final_info": info}
                    obs, info = env.reset()
                    info = {**final, **info}
                else:
                    self.needs_reset[i] = term or trunc
                out.append((obs, float(reward), bool(term), bool(trunc), info))
        return out


def _worker(conn, n: int, scenario, options, overrides, same_step: bool) -> None:
    """A worker process: build a block, then answer ``reset`` / ``step`` / ``close``."""
    try:
        block = EnvBlock(n, scenario, options, overrides, same_step)
        conn.send(("ok", None))
    except BaseException as e:  # reported to the parent, which raises
        conn.send(("error", f"{type(e).__name__}: {e}"))
        return
    while True:
        try:
            cmd, arg = conn.recv()
        except (EOFError, KeyboardInterrupt):
            return
        if cmd == "close":
            conn.send(("ok", None))
            return
        try:
            conn.send(("ok", getattr(block, cmd)(arg)))  # "reset" (seeds) or "step" (actions)
        except (ValueError, TypeError) as e:  # bad input: one line, raised as its own type in the parent
            conn.send((type(e).__name__, f"{type(e).__name__}: {e}"))
        except BaseException as e:  # a bug: its traceback travels
            conn.send(("error", f"{type(e).__name__}: {e}\n{traceback.format_exc()}"))


class SurveyVectorEnv(VectorEnv):
    """N :class:`sim.envs.survey_env.SurveyEnv` stepped in lockstep.

    :class:`SurveyVectorEnv` holds N :class:`sim.envs.survey_env.SurveyEnv` in ``workers``
    processes (1: in this process), each process stepping its contiguous block of envs in turn.
    Unlike ``gymnasium.vector.AsyncVectorEnv`` (one process per env) a process holds many envs,
    and they share what a process can share: the interpreter and its libraries, the compiled
    sonar kernels and one ATR detector per configuration
    (:func:`sim.features.shared_detector.shared_detector`), so a batch of 64 sonar envs fits in
    a few GB where 64 processes would not.

    What is not batched, and why (measured on a 2-core AMD EPYC, shipped ATR model): one
    onnxruntime call on a batch of frames costs more per frame than one call per frame (batch
    4: 1.2x, batch 16: 1.45x the single-frame time: the activations of a batch no longer fit
    the caches), so each env's frames go through the shared detector one by one; and each env's
    sonar casts against its own episode's MuJoCo scene (the Survey env draws a new layout per
    episode), one ``mj_multiRay`` call per frame.

    | | |
    |---|---|
    | observation space | ``Dict`` of the single env's fields, each batched along a leading axis of N |
    | action space | ``Box([-1, 1], (N, 3))`` |
    | autoreset | ``AutoresetMode.NEXT_STEP`` (default): the step after an env's episode ends resets it (its action is ignored; reward 0, not terminated, not truncated); ``SAME_STEP``: the ending step returns the new episode's first observation, the final one in ``info["final_obs"]`` / ``info["final_info"]`` |
    | seeding | ``reset(seed=s)``: env ``i`` is reset with ``s + i``; a list gives one seed per env; None continues each env's generator |
    | determinism | env ``i``'s trajectory depends only on its own seed and actions: the same whatever N, the order of the envs and the number of workers |
    | infos | gymnasium's vector convention: each key an array over envs with a ``_key`` mask |
    | errors | an env's error in a worker names the worker: bad input (``ValueError``, ``TypeError``) in one line of its own type, as with ``workers=1``; anything else a ``RuntimeError`` with the worker's traceback |

    Args:
        num_envs: N >= 1.
        scenario, options, overrides: as :class:`sim.envs.survey_env.SurveyEnv` (the same for
            every env).
        workers: processes holding the envs (1 <= workers <= N; default 1, this process).
        context: ``multiprocessing`` start method for the workers (None: the platform's default).
        autoreset_mode: ``AutoresetMode.NEXT_STEP`` or ``AutoresetMode.SAME_STEP`` (what
            Stable-Baselines3's vector envs do; :mod:`sim.envs.sb3_vec`).

    Raises:
        ValueError: ``num_envs`` < 1, ``workers`` outside [1, num_envs], another autoreset mode,
            overrides not a tuple of strings, a bad seed, reset options; as ``SurveyEnv``.
        gymnasium.error.ResetNeeded: ``step`` before ``reset``.
        gymnasium.error.ClosedEnvironmentError: ``reset`` or ``step`` after ``close``.
        RuntimeError: a worker failed on something other than bad input (its error and traceback
            in the text).
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, num_envs: int, scenario: str | Path | Scenario = "cssn_lawnmower",
                 options: SurveyEnvOptions | dict | None = None, overrides: tuple[str, ...] = (), *,
                 workers: int = 1, context: str | None = None,
                 autoreset_mode: AutoresetMode = AutoresetMode.NEXT_STEP) -> None:
        if not is_int(num_envs) or num_envs < 1:
            raise ValueError(f"num_envs must be an integer >= 1, got {num_envs!r}")
        if not is_int(workers) or not 1 <= workers <= num_envs:
            raise ValueError(f"workers must be an integer in [1, num_envs={num_envs}], got {workers!r}")
        if isinstance(overrides, str) or not all(isinstance(o, str) for o in overrides):
            raise ValueError(f"overrides must be a tuple of 'key.path=value' strings, got {overrides!r}")
        overrides = tuple(overrides)
        if autoreset_mode not in (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP):
            raise ValueError(f"autoreset_mode must be NEXT_STEP or SAME_STEP, got {autoreset_mode!r}")
        self.metadata = {**self.metadata, "autoreset_mode": autoreset_mode}
        same_step = autoreset_mode == AutoresetMode.SAME_STEP
        self.num_envs = int(num_envs)
        self.workers = int(workers)
        self._sizes = [len(b) for b in np.array_split(np.arange(self.num_envs), self.workers)]
        self._block: EnvBlock | None = None
        self._was_reset = False
        self._conns: list = []
        self._procs: list = []
        self.closed = False
        if self.workers == 1:
            self._block = EnvBlock(self.num_envs, scenario, options, overrides, same_step)
            single = self._block.envs[0]
        else:
            single = SurveyEnv(scenario, options, overrides)  # the spaces (and the inputs' checks) here
            ctx = mp.get_context(context)
            for n in self._sizes:
                parent, child = ctx.Pipe()
                p = ctx.Process(target=_worker, args=(child, n, scenario, options, overrides, same_step), daemon=True)
                p.start()
                child.close()
                self._conns.append(parent)
                self._procs.append(p)
            try:
                self._gather("start")
            except BaseException:
                self.close()
                raise
        self.single_observation_space = single.observation_space
        self.single_action_space = single.action_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.decision_interval_s = single.decision_interval_s
        self._fields = tuple(self.single_observation_space.spaces)
        del single  # the block or the workers hold the envs

    # ------------------------------------------------------------------ gymnasium API
    def reset(self, *, seed: int | list[int | None] | None = None, options: dict | None = None
              ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        self._check_open()
        refuse_reset_options(options)
        if seed is None:
            seeds: list[int | None] = [None] * self.num_envs
        elif is_int(seed):
            seeds = [int(seed) + i for i in range(self.num_envs)]
        elif isinstance(seed, list | tuple | np.ndarray):
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"seed: {len(seeds)} seeds for {self.num_envs} envs")
        else:
            raise ValueError(f"seed must be an integer >= 0, a list of {self.num_envs} of them (None allowed), or "
                             f"None; got {seed!r}")
        bad = [s for s in seeds if s is not None and (not is_int(s) or s < 0)]
        if bad:
            raise ValueError(f"seed: each must be an integer >= 0 (or None), got {bad[0]!r}")
        results = self._call("reset", seeds)
        self._was_reset = True
        return self._stack([o for o, _ in results]), self._infos([info for _, info in results])

    def step(self, actions: np.ndarray) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray, np.ndarray,
                                                  dict[str, Any]]:
        self._check_open()
        if not self._was_reset:
            raise ResetNeeded("SurveyVectorEnv: call reset() before step()")
        try:
            a = np.asarray(actions, dtype=np.float32)
        except (TypeError, ValueError):
            raise ValueError(f"actions must be numbers of shape {self.action_space.shape}, got {actions!r}") from None
        if a.shape != self.action_space.shape:
            raise ValueError(f"actions must have shape {self.action_space.shape}, got {a.shape}")
        results = self._call("step", a)
        obs = self._stack([r[0] for r in results])
        rewards = np.array([r[1] for r in results], dtype=np.float64)
        terms = np.array([r[2] for r in results], dtype=bool)
        truncs = np.array([r[3] for r in results], dtype=bool)
        return obs, rewards, terms, truncs, self._infos([r[4] for r in results])

    def close_extras(self, **kwargs: Any) -> None:
        for conn in self._conns:
            try:
                conn.send(("close", None))
                conn.recv()
            except (OSError, EOFError, BrokenPipeError):
                pass
        for p in self._procs:
            p.join(timeout=5)
            if p.is_alive():
                p.terminate()
        self._conns, self._procs = [], []

    # ------------------------------------------------------------------ internals
    def _check_open(self) -> None:
        if self.closed:
            raise ClosedEnvironmentError("SurveyVectorEnv: the env is closed (make a new one)")

    @property
    def envs(self) -> list[SurveyEnv]:
        """The envs, when they live in this process (``workers=1``).

        Raises:
            AttributeError: the envs live in worker processes."""
        if self._block is None:
            raise AttributeError("the envs live in worker processes (workers > 1)")
        return self._block.envs

    def _call(self, cmd: str, per_env) -> list:
        """``EnvBlock.<cmd>`` (``reset``: seeds, ``step``: actions) on every env, in this
        process or scattered to the workers by blocks; the results in env order."""
        if self._block is not None:
            return getattr(self._block, cmd)(per_env)
        k = 0
        for conn, n in zip(self._conns, self._sizes):
            conn.send((cmd, per_env[k:k + n]))
            k += n
        return [r for part in self._gather(cmd) for r in part]

    def _stack(self, items: list[dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
        return {k: np.stack([o[k] for o in items]) for k in self._fields}

    def _infos(self, items: list[dict[str, Any]]) -> dict[str, Any]:
        """The envs' info dicts in gymnasium's vector form (arrays over envs, ``_key`` masks)."""
        infos: dict[str, Any] = {}
        for i, info in enumerate(items):
            infos = self._add_info(infos, info, i)
        return infos

    def _gather(self, what: str) -> list:
        out, errors, kinds = [], [], set()
        for w, conn in enumerate(self._conns):
            try:
                status, payload = conn.recv()
            except EOFError:
                status, payload = "error", "the worker process exited"
            if status == "ok":
                out.append(payload)
            else:
                errors.append(f"worker {w}: {payload}")
                kinds.add(status)
        if errors:
            exc = {"ValueError": ValueError, "TypeError": TypeError}.get(kinds.pop(), RuntimeError) \
                if len(kinds) == 1 else RuntimeError
            raise exc(f"SurveyVectorEnv {what}: " + "; ".join(errors))
        return out


def make_survey_vector_env(num_envs: int, **kwargs: Any) -> SurveyVectorEnv:
    """``gymnasium.make_vec("auvsim/Survey-v1", ...)`` entry point for the ``"custom"`` mode."""
    return SurveyVectorEnv(num_envs, **kwargs)


__all__ = ["EnvBlock", "SurveyVectorEnv", "make_survey_vector_env"]
