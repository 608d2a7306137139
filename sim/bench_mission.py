"""``auvsim bench mission``: closed-loop mission throughput and where the time goes.

Runs the scenario (FLS at its scenario rate, perception included) for a fixed simulated
time, once plain for the real-time factor and once under cProfile for a breakdown.
"""

from __future__ import annotations

import cProfile
import pstats
import time
from typing import Any

from scenarios.schema import Scenario

# (label, (file suffix, function name)) of the stages whose cumulative time is reported.
STAGES: tuple[tuple[str, tuple[str, str]], ...] = (
    ("physics_mj_step", ("~", "<built-in method mujoco._functions.mj_step>")),
    ("vehicle_wrench", ("sim/vehicle.py", "step_inputs")),
    ("vehicle_truth", ("sim/vehicle.py", "truth")),
    ("fls_render", ("sim/sensors/fls.py", "render")),
    ("perception", ("sim/perception.py", "process")),
    ("nav_sensors", ("sim/mission.py", "_fire")),
    ("nav_filter_predict", ("autonomy/navigation/ekf.py", "predict")),
    ("autopilot", ("autonomy/control/autopilot.py", "update")),
    ("allocation", ("autonomy/control/allocation.py", "allocate")),
    ("mission_fsm_guidance", ("autonomy/guidance/mission.py", "update")),
)


def _stage_times(stats: pstats.Stats) -> dict[str, float]:
    out = {label: 0.0 for label, _ in STAGES}
    for (filename, _line, func), (_cc, _nc, _tt, ct, _callers) in stats.stats.items():  # type: ignore[attr-defined]
        for label, (suffix, name) in STAGES:
            if func == name and (suffix == "~" and filename == "~" or filename.endswith(suffix)):
                out[label] += ct
    return out


def run(scenario: Scenario, sim_time_s: float = 120.0, warmup_s: float = 30.0) -> dict[str, Any]:
    """Mission real-time factor over ``sim_time_s`` after ``warmup_s`` (dive and start)."""
    from sim.mission import Mission

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

    prof = cProfile.Profile()
    prof.enable()
    for _ in range(n_steps):
        mission.step()
    prof.disable()
    stats = pstats.Stats(prof)
    total = stats.total_tt  # type: ignore[attr-defined]
    stages = _stage_times(stats)
    # nav sensors are fired from _fire, which also renders the FLS: separate them
    stages["nav_sensors"] = max(stages["nav_sensors"] - stages["fls_render"], 0.0)
    return {
        "scenario": scenario.name,
        "sim_time_s": sim_time_s,
        "wall_time_s": wall,
        "real_time_factor": sim_time_s / wall,
        "physics_rate_hz": scenario.physics.rate_hz,
        "fls_rate_hz": scenario.sensors.fls.rate_hz if scenario.sensors.fls.enabled else 0.0,
        "fls_frames": frames,
        "detector": scenario.autonomy.atr.detector,
        "profile_share": {k: round(v / total, 4) for k, v in stages.items()},
        "profile_ms_per_sim_s": {k: round(1e3 * v / sim_time_s, 2) for k, v in stages.items()},
    }
