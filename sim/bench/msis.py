"""Scanning-sonar benchmark: pings rendered per second and onboard feature-extraction cost.

``auvsim bench msis`` renders a full turn of pings in the scenario's basin (the
``pool_circular`` scene when the scenario given has no ``msis`` sensor) from a pose moving at
0.2 m/s with MuJoCo ray casting, noise and ground truth on, then feeds the pings to the onboard
localiser (sonar buffer + MLESAC circle or IEPF walls) and times each call.
"""

from __future__ import annotations

import time

import numpy as np

from autonomy.frames import rot_from_euler
from autonomy.messages import NavEstimate
from autonomy.msis.localization import MsisLocalizer
from scenarios.load import load_scenario
from scenarios.schema import Scenario
from sim.rng import component_rng
from sim.sensors.msis import MsisSensor
from sim.sensors.raycast import MujocoRayCaster
from sim.scene.world import build_world


def run(scenario: Scenario, n_turns: int = 3) -> dict:
    """Render ``n_turns`` full turns and time rendering and feature extraction.

    Returns:
        dict with ``pings_per_s`` and ``us_per_ping`` (rendering, wall clock), ``cpu_pings_per_s``
        (process CPU time, all threads: steadier on a shared machine), ``turn_render_s``
        (one 400-gradian turn) against ``turn_device_s`` (the device's time for it),
        ``features_p50_ms`` / ``features_p99_ms`` / ``features_max_ms`` (localiser call per ping,
        fits included), ``fit_ms_mean`` (the calls that fitted), ``n_pings``, ``n_fits``, ``method``.
    """
    if scenario.sensors.first_of_kind("msis") is None:
        scenario = load_scenario("pool_circular", [f"seed={scenario.seed}"])
    cfg = scenario.sensors.first_of_kind("msis")
    loc_cfg = scenario.autonomy.msis_localization
    if loc_cfg.method == "none":
        loc_cfg = loc_cfg.model_copy(update={"method": "circle"})
    world = build_world(scenario)
    caster = MujocoRayCaster(world.model, world.data, world.geom_object_id, world.geom_reflectivity,
                             world.vehicle_body_id)
    sensor = MsisSensor(cfg, np.asarray(cfg.mount_pos_body_m), component_rng(scenario.seed, "msis"))
    T = cfg.ping_duration_s
    n = n_turns * int(np.ceil(400 / cfg.step_grad))
    R_nb = rot_from_euler(0.0, 0.0, 0.3)
    start = np.array([-1.0, -1.0, 1.5])
    vel = R_nb @ np.array([0.2, 0.0, 0.0])
    sensor.render(0.0, 0.0, start, R_nb, caster)  # warm-up
    renders, t0, c0 = [], time.perf_counter(), time.process_time()
    for k in range(n):
        renders.append(sensor.render(k * T, sensor.head.next_angle(), start + vel * k * T + R_nb @ sensor.mount_pos_body_m,
                                     R_nb, caster))
    render_s = time.perf_counter() - t0
    render_cpu_s = time.process_time() - c0
    loc = MsisLocalizer(loc_cfg.model_copy(update={"fix_interval_s": 400 / cfg.step_grad * T}),
                        component_rng(scenario.seed, "msis_localizer"))
    cost_ms, fitted = [], []
    for k, r in enumerate(renders):
        nav = NavEstimate(r.ping.t_s, start + vel * k * T, np.array([0.0, 0.0, 0.3]), np.array([0.2, 0.0, 0.0]),
                          np.zeros(3), np.eye(3))
        n_before = len(loc.buffer)
        t1 = time.perf_counter()
        fix = loc.process(r.ping, nav)
        dt_ms = (time.perf_counter() - t1) * 1e3
        cost_ms.append(dt_ms)
        if len(loc.buffer) < n_before or fix is not None:
            fitted.append(dt_ms)
    c = np.asarray(cost_ms)
    return {
        "pings_per_s": round(n / render_s, 1), "us_per_ping": round(render_s / n * 1e6, 1),
        "cpu_pings_per_s": round(n / render_cpu_s, 1),
        "turn_render_s": round(render_s / n * 400 / cfg.step_grad, 3), "turn_device_s": round(400 / cfg.step_grad * T, 2),
        "features_p50_ms": round(float(np.percentile(c, 50)), 4), "features_p99_ms": round(float(np.percentile(c, 99)), 4),
        "features_max_ms": round(float(c.max()), 3), "fit_ms_mean": round(float(np.mean(fitted)), 3) if fitted else None,
        "n_pings": n, "n_fits": len(fitted), "method": loc_cfg.method, "n_samples": sensor.n_samples,
        "scenario": scenario.name,
    }
