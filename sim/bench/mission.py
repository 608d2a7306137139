"""``auvsim bench mission``: closed-loop mission throughput and where the time goes.

Runs the scenario (sensors at their scenario rates, perception included) for a fixed
simulated time twice from the same state: once plain for the real-time factor, once with a
:class:`sim.stage_timer.StageTimer` for the exclusive wall time of each loop stage.
"""

from __future__ import annotations

import time
from typing import Any

from scenarios.schema import Scenario


def run(scenario: Scenario, sim_time_s: float = 120.0, warmup_s: float = 30.0) -> dict[str, Any]:
    """Mission real-time factor over ``sim_time_s`` after ``warmup_s`` (dive and start), and
    the time per simulated second of each stage (``stage_ms_per_sim_s``)."""
    from sim.mission import Mission
    from sim.stage_timer import NULL_TIMER, StageTimer

    timer = StageTimer()
    mission = Mission(scenario)
    mission.reset()
    n_warm = int(round(warmup_s / mission.autonomy_dt_s))
    n_steps = int(round(sim_time_s / mission.autonomy_dt_s))
    for _ in range(n_warm):
        mission.step()
    frames0 = mission.n_fls_frames
    t0 = time.perf_counter()
    for _ in range(n_steps):
        mission.step()
    wall = time.perf_counter() - t0
    frames = mission.n_fls_frames - frames0

    mission.timer = timer
    t0 = time.perf_counter()
    for _ in range(n_steps):
        mission.step()
    timed_wall = time.perf_counter() - t0
    mission.timer = NULL_TIMER
    stages = dict(sorted(timer.seconds.items(), key=lambda kv: -kv[1]))
    fls = scenario.sensors.first_of_kind("fls")
    return {
        "scenario": scenario.name,
        "sim_time_s": sim_time_s,
        "wall_time_s": wall,
        "real_time_factor": sim_time_s / wall,
        "physics_rate_hz": scenario.physics.rate_hz,
        "fls_rate_hz": fls.rate_hz if fls is not None else 0.0,
        "fls_frames": frames,
        "detector": scenario.autonomy.atr.detector,
        "stage_share": {k: round(v / timed_wall, 4) for k, v in stages.items()},
        "stage_ms_per_sim_s": {k: round(1e3 * v / sim_time_s, 2) for k, v in stages.items()},
        "timer_overhead_share": round(max(timed_wall - wall, 0.0) / wall, 4),
    }
