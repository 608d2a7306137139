"""Physics benchmark: hull + Fossen hydrodynamics + thrusters at the scenario's physics rate.

Builds the scenario's world (:class:`sim.scene.physics.Physics`: seabed, walls, targets, hull,
current), then runs ``sim_time_s`` of simulated time on one thread: every step the thrusters
and the hydrodynamic wrench are updated, MuJoCo steps and the current evolves
(:meth:`Physics.advance`).
Thruster commands change at 10 Hz (as a controller would) following a fixed manoeuvre, so
rotor lags are always active. Only the stepping loop is timed; it is repeated ``repeats``
times from the same initial state and the fastest run is reported (as ``timeit`` does: the
machine is shared, slower runs measure other processes), the median alongside.
"""

from __future__ import annotations

import time
from typing import Any

import mujoco
import numpy as np

from scenarios.schema import Scenario
from sim.scene.physics import Physics

CONTROL_RATE_HZ = 10.0


def _command_schedule(n_thr: int, n_updates: int, dt_ctrl_s: float) -> list[list[float]]:
    """Smooth, deterministic commands in [-0.8, 0.8]: one sinusoid per thruster."""
    t = np.arange(n_updates)[:, None] * dt_ctrl_s
    periods_s = 20.0 + 7.0 * np.arange(n_thr)[None, :]
    phase = np.arange(n_thr)[None, :]
    return (0.8 * np.sin(2.0 * np.pi * t / periods_s + phase)).tolist()


def run(scenario: Scenario, sim_time_s: float = 60.0, repeats: int = 3) -> dict[str, Any]:
    """Time the physics loop; returns steps_per_s, real_time_factor, sim_time_s,
    wall_time_s, rate_hz and a per-step breakdown (µs)."""
    if sim_time_s <= 0.0:
        raise ValueError(f"sim_time_s must be > 0, got {sim_time_s}")
    if repeats < 1:
        raise ValueError(f"repeats must be >= 1, got {repeats}")
    physics = Physics(scenario)
    model, data, params, dyn = physics.model, physics.data, physics.params, physics.vehicle
    init_pos = scenario.vehicle.initial_pos_ned
    init_rpy = np.deg2rad(scenario.vehicle.initial_rpy_deg)

    dt_s = physics.dt_s
    rate_hz = 1.0 / dt_s
    n_steps = int(round(sim_time_s * rate_hz))
    every = max(1, int(round(rate_hz / CONTROL_RATE_HZ)))
    schedule = _command_schedule(params.layout.n, n_steps // every + 1, every * dt_s)

    step_inputs, mj_step, advance = dyn.step_inputs, mujoco.mj_step, physics.advance
    n_updates, rest = divmod(n_steps, every)
    walls, cpus = [], []
    for _ in range(repeats):
        physics.reset(init_pos, init_rpy)
        c0, t0 = time.process_time(), time.perf_counter()
        for j in range(n_updates):
            advance(schedule[j], every)
        if rest:
            advance(schedule[n_updates], rest)
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    wall_s = min(walls)

    # Breakdown: the wrench computation alone and mj_step alone, on the final state.
    n_probe = min(n_steps, 5000)
    cmd = schedule[-1]
    t1 = time.perf_counter()
    for _ in range(n_probe):
        step_inputs(cmd, 0.0)
    wrench_us = (time.perf_counter() - t1) / n_probe * 1e6
    data.xfrc_applied[dyn.body_id] = 0.0
    saved = (data.qpos.copy(), data.qvel.copy(), data.time)
    t2 = time.perf_counter()
    for _ in range(n_probe):
        mj_step(model, data)
    mj_us = (time.perf_counter() - t2) / n_probe * 1e6
    data.qpos[:], data.qvel[:], data.time = saved

    warnings = physics.warnings()
    truth = dyn.truth(n_steps * dt_s)
    return {
        "steps_per_s": n_steps / wall_s,
        "real_time_factor": n_steps * dt_s / wall_s,
        "sim_time_s": n_steps * dt_s,
        "wall_time_s": wall_s,
        "rate_hz": rate_hz,
        "n_steps": n_steps,
        "us_per_step": wall_s / n_steps * 1e6,
        "repeats": repeats,
        "real_time_factor_median": n_steps * dt_s / float(np.median(walls)),
        "real_time_factor_cpu": n_steps * dt_s / min(cpus),  # CPU time of this process
        "vehicle_wrench_us": wrench_us,
        "mj_step_us": mj_us,
        "vehicle": params.name,
        "n_geoms": int(model.ngeom),
        "mujoco_warnings": warnings,
        "final_pos_ned": [round(float(x), 4) for x in truth.pos_ned],
    }
