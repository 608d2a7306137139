"""Batched Survey env benchmark: env steps per second, CPU and memory against the batch size.

``auvsim bench vector`` builds :class:`sim.envs.survey_vector.SurveyVectorEnv` with N envs
(default N = 1, 4, 16, 64) in ``min(N, workers)`` processes (default: the CPUs this process
may use), without
and with sonar (FLS, ATR, world model and the sonar image observation), resets it, takes
:data:`WARMUP_STEPS` untimed steps, then times vector steps of the Survey bench's constant
turn. Per N: ``steps_per_s`` (env steps, all envs, per wall second), ``cpu_ms_per_step``
(CPU of the processes holding envs per env step), ``rss_mb`` (resident memory of those
processes, this one included, summed: pages they share are counted in each) and, with and
without sonar in the same run, ``sonar_ratio`` (steps/s with sonar over steps/s without).
"""

from __future__ import annotations

import os
import sys
import time
from typing import Any

import numpy as np
import psutil

from scenarios.schema import Scenario
from sim.bench.gym import SURVEY_ACTION, process_cpu_s
from sim.process.cpus import usable_cpus
from sim.envs.survey_vector import SurveyVectorEnv

WARMUP_STEPS = 1
BATCH_SIZES = (1, 4, 16, 64)


def _time(scenario: Scenario, n_envs: int, workers: int, sonar: bool, env_steps: int) -> dict[str, Any]:
    t0 = time.perf_counter()
    venv = SurveyVectorEnv(n_envs, scenario, {"sonar": sonar}, workers=min(workers, n_envs))
    try:
        venv.reset(seed=0)
        build_s = time.perf_counter() - t0
        pids = [os.getpid()] + [p.pid for p in venv._procs]
        act = np.tile(SURVEY_ACTION, (n_envs, 1))
        for _ in range(WARMUP_STEPS):
            venv.step(act)
        n_steps = max(2, -(-env_steps // n_envs))
        cpu0, t0 = sum(process_cpu_s(p) or 0.0 for p in pids), time.perf_counter()
        for _ in range(n_steps):
            venv.step(act)
        wall = time.perf_counter() - t0
        cpu = sum(process_cpu_s(p) or 0.0 for p in pids) - cpu0
        rss = sum(psutil.Process(p).memory_info().rss for p in pids) / 2**20
    finally:
        venv.close()
    total = n_steps * n_envs
    return {"n_envs": n_envs, "workers": min(workers, n_envs), "steps_per_s": round(total / wall, 2),
            "cpu_ms_per_step": round(1e3 * cpu / total, 2), "rss_mb": round(rss), "build_and_reset_s": round(build_s, 1),
            "env_steps_timed": total}


def run(scenario: Scenario, *, workers: int | None = None, batch_sizes: tuple[int, ...] = BATCH_SIZES,
        env_steps: int = 64) -> dict[str, Any]:
    """Time the batched env at each of ``batch_sizes`` without and with sonar (``env_steps``
    env steps at least, two vector steps at least, per figure); ``workers``: processes
    (default the cores). Returns ``{"no_sonar": [...], "sonar": [...], "sonar_ratio": [...]}``."""
    workers = workers or usable_cpus()
    out: dict[str, Any] = {"no_sonar": [], "sonar": []}
    for n in batch_sizes:
        for key, sonar in (("no_sonar", False), ("sonar", True)):
            print(f"bench vector: N={n} {key}", file=sys.stderr, flush=True)
            out[key].append(_time(scenario, n, workers, sonar, env_steps if not sonar else max(env_steps // 4, n)))
    out["sonar_ratio"] = [{"n_envs": a["n_envs"], "ratio": round(b["steps_per_s"] / a["steps_per_s"], 3)}
                          for a, b in zip(out["no_sonar"], out["sonar"])]
    out["load_avg_1min"] = os.getloadavg()[0] if hasattr(os, "getloadavg") else None
    return out
