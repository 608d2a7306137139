"""Ray backends on a scenario's scene: MuJoCo ``mj_multiRay`` against Embree (``physics.ray_caster``).

Casts the FLS base ray fan of ``auvsim bench fls`` (same survey poses) through
:class:`sim.sensors.raycast.MujocoRayCaster` with ``backend="mujoco"`` and
``backend="embree"`` (:mod:`sim.sensors.embree_scene`: meshes, boxes and planes as
triangles), alternating frame by frame, and prints one JSON object: CPU time per frame of
each, the speed-up, the largest hit-distance difference and the share of rays whose hit/miss
or object differ. Needs ``pip install 'auvsim[fast]'`` (embreex).

    python scripts/bench_ray_backends.py [--scenario cssn_lawnmower] [--frames 150]
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sim.cli.app import run_script, script_parser  # noqa: E402
from sim.cli.args import positive_int  # noqa: E402
from sim.cli.errors import CliError  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    """Parse ``argv`` and compare; bad arguments: one line, exit status 2."""
    ap = script_parser("bench_ray_backends.py", __doc__.splitlines()[0])
    ap.add_argument("--scenario", default="cssn_lawnmower", help="scenario name or path (default cssn_lawnmower)")
    ap.add_argument("--frames", type=positive_int, default=150, help="frames (default 150)")
    return run_script(ap, compare, argv)


def compare(args) -> int:
    """Time both backends on the fan as :func:`main` parsed ``args`` ask."""
    import numpy as np

    from autonomy.frames import rot_from_euler
    from scenarios.config.fls import FlsConfig
    from scenarios.load import load_scenario
    from sim.scene.world import build_world
    from sim.sensors import embree_scene
    from sim.sensors.fls import FlsSensor
    from sim.sensors.raycast import MujocoRayCaster

    if not embree_scene.available():
        raise CliError("this comparison needs Embree's binding: pip install 'auvsim[fast]' (embreex, x86-64 wheels)")
    scenario = load_scenario(args.scenario, [])
    fls = scenario.sensors.get("fls")
    if fls is None or fls.kind != "fls":
        raise CliError(f"--scenario {args.scenario}: has no forward-looking sonar entry sensors.fls (kind fls) whose "
                       "fan to cast; use cssn_lawnmower or a scenario with one")
    world = build_world(scenario)
    casters = {b: MujocoRayCaster(world.model, world.data, world.geom_object_id, world.geom_reflectivity,
                                  world.vehicle_body_id, backend=b) for b in ("mujoco", "embree")}
    cfg = FlsConfig(**{**fls.model_dump(), "range_window_m": (1.0, 30.0)})
    sensor = FlsSensor(cfg, rng=np.random.default_rng(0))
    centroids = np.array([o.centroid_ned for o in world.objects]) if world.objects else np.zeros((1, 3))
    seabed_z = float(world.seabed.depth_at(*centroids[:, :2].mean(axis=0)))
    R_ns = rot_from_euler(0.0, 0.0, np.pi / 2) @ sensor.R_bs
    dirs = sensor.rays.dirs_sonar @ R_ns.T
    cpu = dict.fromkeys(casters, 0.0)
    first = np.array([centroids[:, 0].mean(), centroids[:, 1].min() - 6.0, seabed_z - 2.0])
    for c in casters.values():  # warm-up: the BVH build, compiled kernels
        c.cast(first, dirs, sensor.geometry.range_max_m)
    worst, differ, n = 0.0, 0, 0
    for i in range(args.frames):  # the survey creep of auvsim bench fls
        origin = np.array([centroids[:, 0].mean(), centroids[:, 1].min() - 6.0 + 0.5 / 3.0 * i, seabed_z - 2.0])
        hits = {}
        for b, c in casters.items():
            c0 = time.process_time()
            hits[b] = c.cast(origin, dirs, sensor.geometry.range_max_m)
            cpu[b] += time.process_time() - c0
        a, e = hits["mujoco"], hits["embree"]
        both = np.isfinite(a.dist_m) & np.isfinite(e.dist_m)
        if both.any():
            worst = max(worst, float(np.abs(a.dist_m[both] - e.dist_m[both]).max()))
        differ += int(np.sum((np.isfinite(a.dist_m) != np.isfinite(e.dist_m)) | (a.object_id != e.object_id)))
        n += len(dirs)
    if not casters["embree"].uses_embree:
        raise CliError(f"--scenario {args.scenario}: its scene has geoms Embree does not take here (spheres, "
                       "cylinders, height fields) or moves: MuJoCo cast both")
    print(json.dumps({"scenario": scenario.name, "rays_per_frame": int(len(dirs)), "frames": args.frames,
                      "mujoco_cpu_ms_per_frame": round(1e3 * cpu["mujoco"] / args.frames, 3),
                      "embree_cpu_ms_per_frame": round(1e3 * cpu["embree"] / args.frames, 3),
                      "embree_speedup": round(cpu["mujoco"] / cpu["embree"], 2),
                      "max_hit_distance_difference_m": worst, "rays_differing_share": differ / n}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
