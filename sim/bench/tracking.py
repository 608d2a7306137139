"""Tracker update-time benchmark (``auvsim bench tracking``).

Paper 004's rates on a synthetic track: a 10 Hz filter tick (pose + estimate + ROI), a sonar
detection on ~30 % of ticks, a USBL fix every 2 s delivered 0.3 s late (re-processing the
history after it). Timed per tick over 300 s of target motion, in wall-clock time (what a
loaded machine's scheduler adds shows in its p99) and in the thread's CPU time
(``time.thread_time``: the tracker's own cost).
"""

from __future__ import annotations

import math
import time

import numpy as np

from autonomy.messages import UsblMsg
from autonomy.tracking import TargetTracker, TrackingConfig


def run(seed: int = 0, duration_s: float = 300.0) -> dict:
    """p50/p99/max of the per-tick tracker time, wall clock (``p50_ms`` ...) and thread CPU
    time (``cpu_p50_ms`` ...), ms, and the counts of updates."""
    rng = np.random.default_rng(seed)
    tr = TargetTracker(TrackingConfig(enabled=True, mode="fused", transponder="diver"))
    pending: list[tuple[float, UsblMsg]] = []
    times, cpu_times = [], []
    for k in range(int(duration_s * 10) + 1):
        t = 0.1 * k
        tgt = np.array([8.0 + 2.0 * math.sin(0.03 * t), 2.0 * math.cos(0.03 * t), 5.0])
        z = np.array([np.linalg.norm(tgt - [0, 0, 5.0]), math.atan2(tgt[1], tgt[0]), 0.0])
        if k % 20 == 0:
            zu = z + rng.normal(0, [0.15, 0.02, 0.02])
            pending.append((t + 0.3, UsblMsg(t, *zu, transponder="diver")))
        t0, c0 = time.perf_counter(), time.thread_time()
        tr.record_pose(t, [0.0, 0.0, 5.0], [0.0, 0.0, 0.0])
        while pending and pending[0][0] <= t + 1e-9:
            tr.on_usbl(pending.pop(0)[1])
        if rng.random() < 0.3:
            zs = z + rng.normal(0, [0.05, 0.005, 0.0])
            tr.on_sonar(t, zs[0], zs[1])
        tr.estimate(t)
        tr.roi(t)
        times.append(time.perf_counter() - t0)
        cpu_times.append(time.thread_time() - c0)
    ms, cpu_ms = 1e3 * np.array(times), 1e3 * np.array(cpu_times)
    used = tr.used_counts()
    return {"ticks": len(ms), "p50_ms": round(float(np.percentile(ms, 50)), 4),
            "p99_ms": round(float(np.percentile(ms, 99)), 4), "max_ms": round(float(ms.max()), 4),
            "cpu_p50_ms": round(float(np.percentile(cpu_ms, 50)), 4),
            "cpu_p99_ms": round(float(np.percentile(cpu_ms, 99)), 4), "cpu_max_ms": round(float(cpu_ms.max()), 4),
            "goal_p99_ms": 1.0, "usbl_used_in_history": used["usbl"], "sonar_used_in_history": used["sonar"]}
