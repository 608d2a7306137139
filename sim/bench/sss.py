"""Side-scan rendering benchmark: pings per second on one core over a scenario's scene.

``auvsim bench sss`` builds the scenario's MuJoCo scene (the ``cssn_lawnmower`` basin by
default), flies a level survey leg across its targets at ``altitude_m`` and renders
side-scan pings (1000 bins per side by default, noise on, labels included).
"""

from __future__ import annotations

import time

import numpy as np

from autonomy.frames import rot_from_euler
from scenarios.config.sss import SssConfig
from scenarios.schema import Scenario
from sim.bench.fls import _TimedCaster
from sim.rng import component_rng
from sim.sensors.raycast import MujocoRayCaster
from sim.sensors.sss import SssSensor
from sim.scene.world import build_world


def run(scenario: Scenario, n_pings: int = 400, n_bins: int = 1000, range_max_m: float = 30.0,
        altitude_m: float = 2.0) -> dict:
    """Render ``n_pings`` pings and report throughput.

    Returns:
        dict with ``pings_per_s`` and ``cpu_pings_per_s`` (wall clock and process CPU time),
        ``ms_per_ping``, ``rays_cast_per_ping``, ``raw_raycast_fraction``, ``n_bins`` per side,
        ``range_max_m``, ``labelled_bins_per_ping`` (bins holding an object id, both sides).
    """
    cfg = SssConfig(n_bins=n_bins, range_max_m=range_max_m)
    world = build_world(scenario)
    caster = _TimedCaster(MujocoRayCaster(world.model, world.data, world.geom_object_id, world.geom_reflectivity,
                                          world.vehicle_body_id))
    sensor = SssSensor(cfg, (0.0, 0.0, 0.0), component_rng(scenario.seed, "sss"))
    centroids = np.array([o.centroid_ned for o in world.objects]) if world.objects else np.zeros((1, 3))
    seabed_z = float(world.seabed.depth_at(*centroids[:, :2].mean(axis=0)))
    start = np.array([centroids[:, 0].min() - 5.0, centroids[:, 1].mean(), seabed_z - altitude_m])
    R_nb = rot_from_euler(0.0, 0.0, 0.0)  # heading north, targets abeam
    step_m = 1.5 / cfg.rate_hz

    def pose(i: int) -> np.ndarray:
        return start + np.array([step_m * i, 0.0, 0.0])

    sensor.render(0.0, pose(0), R_nb, caster, world.objects)  # warm-up
    caster.time_s, caster.n_rays = 0.0, 0
    labelled = 0
    t0, c0 = time.perf_counter(), time.process_time()
    for i in range(n_pings):
        out = sensor.render(i / cfg.rate_hz, pose(i), R_nb, caster, world.objects)
        labelled += int(np.count_nonzero(out.labels >= 0))
    total = time.perf_counter() - t0
    cpu = time.process_time() - c0
    return {
        "pings_per_s": round(n_pings / total, 1),
        "cpu_pings_per_s": round(n_pings / cpu, 1),
        "ms_per_ping": round(1e3 * total / n_pings, 3),
        "rays_cast_per_ping": round(caster.n_rays / n_pings),
        "raw_raycast_fraction": round(caster.time_s / total, 4),
        "n_bins": n_bins,
        "range_max_m": range_max_m,
        "ping_rate_hz": round(cfg.rate_hz, 2),
        "labelled_bins_per_ping": round(labelled / n_pings, 1),
        "n_pings": n_pings,
    }
