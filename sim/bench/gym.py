"""Gym benchmark: env steps per second and real-time factor of the auvsim environments.

Variants (each at its default decision interval, one process unless stated):

* ``waypoint``: ``auvsim/Waypoint-v1``, uniform random actions;
* ``survey``: ``auvsim/Survey-v1`` without sonar, a slow constant turn (stays in the area);
* ``survey_sonar``: the same with FLS, ATR, PMHA and the sonar image observation;
* ``vector``: ``Waypoint-v1``, ``Survey-v1`` without and with sonar in an ``AsyncVectorEnv``
  with one worker process per core (2 by default, ``workers``): total env steps per second
  across workers, and ``speedup``: that over the single env of the same run.

Single-env figures time ``step`` only (resets are reported apart); vector figures
include the workers' automatic resets. Both start after ``WARMUP_STEPS`` untimed steps (a
fresh env's first steps pay one-off costs: the first sonar frames, caches).

On a shared machine the wall-clock ``speedup`` says how many cores the vector env got, not
how many it could use; CPU time tells the two apart. Each figure also carries
``cpu_ms_per_step`` (single env: this process's CPU time per step; vector: the workers' CPU
time, from ``/proc/PID/stat``, per env step), and the vector ones ``cpu_speedup`` (``n_envs``
times the single env's CPU per step over the workers': the speedup with ``n_envs`` free
cores; ``n_envs`` when a worker step costs what a single-env step costs) and
``worker_busy_fraction`` (workers' CPU time over ``n_envs`` x wall time: 1 when every worker
ran all the time, lower when they waited for a core or for the parent). ``load_avg_1min``
is the machine's load at the start. ``profile`` lists, per single-env variant, the
functions with the most cumulative time in a short cProfile'd run.
"""

from __future__ import annotations

import cProfile
import os
import pstats
import time
from functools import partial
from typing import Any

import gymnasium as gym
import numpy as np

from scenarios.schema import Scenario
from sim.envs.survey_env import SurveyEnv, SurveyEnvOptions
from sim.envs.waypoint_env import WaypointEnv

WARMUP_STEPS = 2  # untimed steps after the first reset (one-off costs of a fresh env)
SURVEY_ACTION = np.array([0.0, 0.05, 0.0], dtype=np.float32)  # 0.5 m/s, 0.75 deg/s turn, 2 m altitude


def _policy(env: gym.Env, rng: np.random.Generator):
    """Survey: the constant turn; otherwise uniform random actions."""
    if isinstance(env.unwrapped, SurveyEnv):
        return lambda: SURVEY_ACTION
    return lambda: rng.uniform(-1.0, 1.0, env.action_space.shape).astype(np.float32)


def _time_env(env: gym.Env, n_steps: int, dt_s: float, seed: int) -> dict[str, float]:
    """Step time only (``steps_per_s``, ``real_time_factor``); resets timed apart."""
    rng = np.random.default_rng(seed)
    act = _policy(env, rng)
    t0 = time.perf_counter()
    env.reset(seed=seed)
    reset_s = [time.perf_counter() - t0]
    for _ in range(WARMUP_STEPS):
        _, _, term, trunc, _ = env.step(act())
        if term or trunc:
            env.reset()
    step_s = reset_cpu_s = 0.0
    # CPU time is read around the whole loop, not around each step: reading it is a system
    # call, where a loaded machine preempts, and per step that would move the waits for a core
    # out of the timed steps
    cpu0 = time.process_time()
    for _ in range(n_steps):
        t0 = time.perf_counter()
        _, _, term, trunc, _ = env.step(act())
        step_s += time.perf_counter() - t0
        if term or trunc:
            c0, t0 = time.process_time(), time.perf_counter()
            env.reset()
            reset_s.append(time.perf_counter() - t0)
            reset_cpu_s += time.process_time() - c0
    cpu_s = time.process_time() - cpu0 - reset_cpu_s
    return {"steps_per_s": n_steps / step_s, "real_time_factor": n_steps * dt_s / step_s, "n_steps": n_steps,
            "decision_interval_s": dt_s, "step_wall_time_s": step_s, "cpu_ms_per_step": 1e3 * cpu_s / n_steps,
            "resets": len(reset_s), "reset_mean_s": float(np.mean(reset_s))}


def process_cpu_s(pid: int) -> float | None:
    """User + system CPU time (s) of process ``pid`` from ``/proc/PID/stat`` (Linux); None
    where there is no such file."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii") as f:
            fields = f.read().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")  # utime, stime (fields 14, 15)


def _workers_cpu_s(venv: gym.vector.AsyncVectorEnv) -> float | None:
    times = [process_cpu_s(p.pid) for p in venv.processes]
    return None if any(t is None for t in times) else float(sum(times))


def _time_vector(fn, n_envs: int, n_steps: int, dt_s: float, act_dim: int, constant: np.ndarray | None) -> dict[str, Any]:
    venv = gym.vector.AsyncVectorEnv([fn] * n_envs)
    rng = np.random.default_rng(0)

    def action() -> np.ndarray:
        a = np.tile(constant, (n_envs, 1)) if constant is not None else rng.uniform(-1, 1, (n_envs, act_dim))
        return a.astype(np.float32)

    try:
        venv.reset(seed=list(range(n_envs)))
        for _ in range(WARMUP_STEPS):
            venv.step(action())
        cpu0, t0 = _workers_cpu_s(venv), time.perf_counter()
        for _ in range(n_steps):
            venv.step(action())
        wall = time.perf_counter() - t0
        cpu1 = _workers_cpu_s(venv)
    finally:
        venv.close()
    total = n_steps * n_envs
    out: dict[str, Any] = {"n_envs": n_envs, "steps_per_s": total / wall, "real_time_factor": total * dt_s / wall,
                           "n_steps": total, "wall_time_s": wall}
    if cpu0 is not None and cpu1 is not None:
        out["cpu_ms_per_step"] = 1e3 * (cpu1 - cpu0) / total
        out["worker_busy_fraction"] = (cpu1 - cpu0) / (n_envs * wall)
    return out


def _profile(env: gym.Env, n_steps: int, top: int = 8) -> list[dict[str, Any]]:
    rng = np.random.default_rng(1)
    act = _policy(env, rng)
    env.reset(seed=1)
    prof = cProfile.Profile()
    prof.enable()
    for _ in range(n_steps):
        _, _, term, trunc, _ = env.step(act())
        if term or trunc:
            env.reset()
    prof.disable()
    stats = pstats.Stats(prof)
    total = max(stats.total_tt, 1e-12)
    rows = sorted(stats.stats.items(), key=lambda kv: kv[1][3], reverse=True)
    out = []
    for (path, line, name), (_, _, tt, ct, _) in rows:
        own_step = name in ("step", "begin_step", "advance", "end_step") and path.endswith(("survey_env.py", "survey_task.py", "waypoint_env.py",
                                                     "waypoint_task.py"))
        if name == "<module>" or own_step:
            continue  # the env's own step (and its phases) is 100 %
        out.append({"function": f"{os.path.relpath(path) if os.path.isabs(path) else path}:{line}({name})",
                    "cumulative_fraction": round(ct / total, 3), "self_fraction": round(tt / total, 3)})
        if len(out) >= top:
            break
    return out


def run(scenario: Scenario, *, waypoint_steps: int = 3000, survey_steps: int = 60, sonar_steps: int = 15,
        workers: int | None = None, profile: bool = True) -> dict[str, Any]:
    """Time every variant on ``scenario``; returns
    ``{"waypoint", "survey", "survey_sonar", "vector", "profile"}`` (each with
    ``steps_per_s`` and ``real_time_factor``); ``workers``: vector-env processes (default:
    the cores, at most 2)."""
    n_envs = workers or min(os.cpu_count() or 1, 2)
    load_avg = os.getloadavg()[0] if hasattr(os, "getloadavg") else None
    wp = WaypointEnv(scenario)
    sv = SurveyEnv(scenario, SurveyEnvOptions(sonar=False))
    sv_sonar = SurveyEnv(scenario, SurveyEnvOptions(sonar=True))
    result: dict[str, Any] = {
        "waypoint": _time_env(wp, waypoint_steps, wp.decision_interval_s, 0),
        "survey": _time_env(sv, survey_steps, sv.decision_interval_s, 0),
        "survey_sonar": _time_env(sv_sonar, sonar_steps, sv_sonar.decision_interval_s, 0),
    }
    result["vector"] = {
        "waypoint": _time_vector(partial(WaypointEnv, scenario), n_envs, waypoint_steps // n_envs,
                                 wp.decision_interval_s, wp.n_act, None),
        "survey": _time_vector(partial(SurveyEnv, scenario, SurveyEnvOptions(sonar=False)), n_envs,
                               survey_steps // n_envs, sv.decision_interval_s, 3, SURVEY_ACTION),
        "survey_sonar": _time_vector(partial(SurveyEnv, scenario, SurveyEnvOptions(sonar=True)), n_envs,
                                     max(sonar_steps // n_envs, 2), sv_sonar.decision_interval_s, 3, SURVEY_ACTION),
    }
    for key in ("waypoint", "survey", "survey_sonar"):
        vec, single = result["vector"][key], result[key]
        vec["speedup"] = vec["steps_per_s"] / single["steps_per_s"]
        if "cpu_ms_per_step" in vec and vec["cpu_ms_per_step"] > 0.0:
            vec["cpu_speedup"] = n_envs * single["cpu_ms_per_step"] / vec["cpu_ms_per_step"]
    result["vector"].update(steps_per_s=result["vector"]["waypoint"]["steps_per_s"],
                            real_time_factor=result["vector"]["waypoint"]["real_time_factor"])
    result["load_avg_1min"] = load_avg
    if profile:
        result["profile"] = {"waypoint": _profile(wp, 500), "survey": _profile(sv, 15),
                             "survey_sonar": _profile(sv_sonar, 5)}
    return result
