"""``auvsim bench mission``: closed-loop mission throughput and where the time goes.

Runs the scenario (sensors at their scenario rates, perception included unless ``sonar`` is
off) for a fixed simulated time after a warm-up: once plain for the real-time factor, once with
a :class:`sim.events.stage_timer.StageTimer` for the exclusive wall time of each loop stage. The loop is
that of ``auvsim run --no-scoring --no-rerun``: its one observer is the trajectory log, so the
sonar renders no ground truth of the objects (nothing reads it; :class:`sim.mission.Mission`).

With ``workers`` > 1 a second mission of the same scenario and seed runs the pipelined loop
(:mod:`sim.process.sonar_pipeline`); the serial and the pipelined loop are timed in alternating
segments of the same run, so a busy machine slows both alike, and the figure to read is their
ratio (``workers_speedup``). CPU time is reported beside wall time (``cpu_real_time_factor``:
simulated seconds per CPU second of this process, all its threads; for the pipelined loop, of
the mission process and its two workers together, with each process's share under
``cpu_s_by_process``). On a shared machine the wall figures depend on the other load; the CPU
figures give what the cores allow: ``cores_bound_real_time_factor`` is the simulated time over
the larger of the busiest process's CPU time and the total CPU time spread over all cores,
the pipelined loop's real-time factor on an otherwise idle machine when nothing waits.
"""

from __future__ import annotations

import os
import time
from typing import Any

from scenarios.schema import Scenario
from sim.outputs.trajectory_log import TrajectoryLog
from sim.events.stage_timer import NULL_TIMER, StageTimer

SEGMENTS = 4  # alternating timed segments per loop when comparing serial and pipelined


def _cpu_s(pids: list[int]) -> list[float]:
    """CPU seconds (user + system) used so far by each process of ``pids``; this process's own
    from ``time.process_time`` (nanosecond clock: psutil's clock-tick counts read 0 over a short
    segment)."""
    import psutil

    me = os.getpid()
    return [time.process_time() if pid == me else sum(psutil.Process(pid).cpu_times()[:2])
            for pid in pids]


def _segment(mission, n_steps: int) -> tuple[float, list[float]]:
    """(wall s, CPU s of this process and of each pipeline worker) of ``n_steps`` steps
    (pipelined frames finished)."""
    pids = [os.getpid()] + mission.worker_pids
    t0, c0 = time.perf_counter(), _cpu_s(pids)
    for _ in range(n_steps):
        mission.step()
    mission.flush()
    return time.perf_counter() - t0, [b - a for a, b in zip(c0, _cpu_s(pids))]


def run(scenario: Scenario, sim_time_s: float = 120.0, warmup_s: float = 30.0, *, sonar: bool = True,
        workers: int = 1) -> dict[str, Any]:
    """Mission real-time factor over ``sim_time_s`` after ``warmup_s`` (dive and start), and
    the time per simulated second of each stage (``stage_ms_per_sim_s``).

    Args:
        scenario: the scenario to fly (its seed).
        sim_time_s, warmup_s: timed and untimed simulated seconds.
        sonar: False disables every forward-looking sonar (and so perception).
        workers: > 1 also times the pipelined loop with that many threads against the serial one.

    Raises:
        ValueError: ``workers`` < 1.
    """
    from sim.mission import Mission

    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    if not sonar:
        sensors = {name: (cfg.model_copy(update={"enabled": False}) if cfg.kind == "fls" else cfg)
                   for name, cfg in scenario.sensors.root.items()}
        scenario = scenario.model_copy(update={"sensors": type(scenario.sensors)(sensors)})
    # what ``auvsim run --no-scoring --no-rerun`` runs: the trajectory log as the only observer
    # (so the sonar skips the ground truth no observer reads; its progress line is off here)
    loops = [Mission(scenario, observers=[TrajectoryLog()])] + (
        [Mission(scenario, observers=[TrajectoryLog()], workers=workers)] if workers > 1 else [])
    n_warm = int(round(warmup_s / loops[0].autonomy_dt_s))
    n_steps = int(round(sim_time_s / loops[0].autonomy_dt_s))
    frames0 = []
    for mission in loops:
        mission.reset()
        for _ in range(n_warm):
            mission.step()
        mission.flush()
        frames0.append(mission.n_fls_frames)
    wall, cpu = [0.0] * len(loops), [[0.0] for _ in loops]
    n_seg = SEGMENTS if len(loops) > 1 else 1
    for k in range(n_seg):
        n = n_steps // n_seg + (1 if k < n_steps % n_seg else 0)
        for i in (range(len(loops)) if k % 2 == 0 else reversed(range(len(loops)))):
            w, c = _segment(loops[i], n)
            wall[i] += w
            cpu[i] = [a + b for a, b in zip(c, cpu[i])] + c[len(cpu[i]):]
    serial = loops[0]
    frames = serial.n_fls_frames - frames0[0]

    timer = StageTimer()
    serial.timer = timer
    t0 = time.perf_counter()
    for _ in range(n_steps):
        serial.step()
    timed_wall = time.perf_counter() - t0
    serial.timer = NULL_TIMER
    stages = dict(sorted(timer.seconds.items(), key=lambda kv: -kv[1]))
    fls = scenario.sensors.first_of_kind("fls")
    result: dict[str, Any] = {
        "scenario": scenario.name,
        "sonar": fls is not None,
        "sim_time_s": sim_time_s,
        "wall_time_s": wall[0],
        "real_time_factor": sim_time_s / wall[0],
        "cpu_real_time_factor": sim_time_s / sum(cpu[0]),
        "physics_rate_hz": scenario.physics.rate_hz,
        "fls_rate_hz": fls.rate_hz if fls is not None else 0.0,
        "fls_frames": frames,
        "detector": scenario.autonomy.atr.detector,
        "stage_share": {k: round(v / timed_wall, 4) for k, v in stages.items()},
        "stage_ms_per_sim_s": {k: round(1e3 * v / sim_time_s, 2) for k, v in stages.items()},
        "timer_overhead_share": round(max(timed_wall - wall[0], 0.0) / wall[0], 4),
    }
    if len(loops) > 1:
        piped = loops[1]
        cores = os.cpu_count() or 1
        names = ["mission", "render", "detection"][:len(cpu[1])]
        result["workers"] = {
            "workers": workers,
            "pipelined": piped.pipelined,
            "real_time_factor": sim_time_s / wall[1],
            "cpu_real_time_factor": sim_time_s / sum(cpu[1]),
            "cpu_s_by_process": {n: round(c, 3) for n, c in zip(names, cpu[1])},
            "cores_bound_real_time_factor": sim_time_s / max(max(cpu[1]), sum(cpu[1]) / cores),
            "serial_real_time_factor": sim_time_s / wall[0],
            "serial_cpu_real_time_factor": sim_time_s / sum(cpu[0]),
            "workers_speedup": wall[0] / wall[1],
            "cores_bound_speedup": sum(cpu[0]) / max(max(cpu[1]), sum(cpu[1]) / cores),
            "fls_frames": piped.n_fls_frames - frames0[1],
        }
        piped.close()
    return result
