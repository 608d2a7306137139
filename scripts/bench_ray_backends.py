"""Ray backends on the shipped scene: MuJoCo ``mj_multiRay`` against Embree (``embreex``).

Casts the FLS base ray fan of ``auvsim bench fls`` (same survey poses) with both backends and
prints CPU time per frame, the speed-up and the largest hit-distance difference. Embree gets
the scene's acoustic geoms as triangles: meshes as they are, boxes as 12 triangles, the plane
as a 1 km square; other primitives are not tessellated (the script refuses such scenes).
Needs ``pip install embreex`` (not a dependency of auvsim).

    python scripts/bench_ray_backends.py [--scenario cssn_lawnmower] [--frames 150]
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import mujoco
import numpy as np

BOX_FACES = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])


def scene_triangles(model, data, acoustic) -> np.ndarray:
    """(n, 3, 3) world-frame triangles of the acoustic geoms (mesh, box, plane).

    Raises:
        SystemExit: a geom of another type (it would need tessellating).
    """
    tris = []
    for g in np.flatnonzero(acoustic):
        R, p, kind = data.geom_xmat[g].reshape(3, 3), data.geom_xpos[g], model.geom_type[g]
        if kind == mujoco.mjtGeom.mjGEOM_MESH:
            mid = model.geom_dataid[g]
            v0, nv = model.mesh_vertadr[mid], model.mesh_vertnum[mid]
            f0, nf = model.mesh_faceadr[mid], model.mesh_facenum[mid]
            tris.append((model.mesh_vert[v0:v0 + nv] @ R.T + p)[model.mesh_face[f0:f0 + nf]])
        elif kind == mujoco.mjtGeom.mjGEOM_BOX:
            corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * model.geom_size[g]
            tris.append((corners @ R.T + p)[BOX_FACES])
        elif kind == mujoco.mjtGeom.mjGEOM_PLANE:
            corners = np.array([[-500.0, -500.0, 0.0], [500.0, -500.0, 0.0], [500.0, 500.0, 0.0], [-500.0, 500.0, 0.0]])
            tris.append((corners @ R.T + p)[np.array([[0, 1, 2], [0, 2, 3]])])
        else:
            print(f"--scenario: geom {g} is a {mujoco.mjtGeom(kind).name}, which this comparison does not "
                  "tessellate (meshes, boxes and planes only)", file=sys.stderr)
            raise SystemExit(2)
    return np.concatenate(tris).astype(np.float32)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="cssn_lawnmower")
    ap.add_argument("--frames", type=int, default=150)
    args = ap.parse_args()
    try:
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh
    except ImportError:
        print("this comparison needs Embree's Python binding: pip install embreex", file=sys.stderr)
        return 2
    from autonomy.frames import rot_from_euler
    from scenarios.config.fls import FlsConfig
    from scenarios.load import load_scenario
    from sim.sensors.fls import FlsSensor
    from sim.sensors.raycast import BACKGROUND_ID, MujocoRayCaster
    from sim.scene.world import build_world

    scenario = load_scenario(args.scenario, [])
    world = build_world(scenario)
    mujoco.mj_forward(world.model, world.data)
    caster = MujocoRayCaster(world.model, world.data, world.geom_object_id, world.geom_reflectivity,
                             world.vehicle_body_id)
    acoustic = (world.geom_object_id >= BACKGROUND_ID) & (caster.geomgroup[np.clip(world.model.geom_group, 0, 5)] > 0)
    triangles = scene_triangles(world.model, world.data, acoustic)
    scene = rtcore_scene.EmbreeScene()
    TriangleMesh(scene, triangles)

    cfg = FlsConfig(**{**scenario.sensors.fls.model_dump(), "range_window_m": (1.0, 30.0)})
    sensor = FlsSensor(cfg, rng=np.random.default_rng(0))
    centroids = np.array([o.centroid_ned for o in world.objects])
    seabed_z = float(world.seabed.depth_at(*centroids[:, :2].mean(axis=0)))
    R_ns = rot_from_euler(0.0, 0.0, np.pi / 2) @ sensor.R_bs
    dirs = sensor.rays.dirs_sonar @ R_ns.T
    t_mj = t_em = 0.0
    worst = 0.0
    for i in range(args.frames):  # the survey creep of auvsim bench fls
        origin = np.array([centroids[:, 0].mean(), centroids[:, 1].min() - 6.0 + 0.5 / 3.0 * i, seabed_z - 2.0])
        c0 = time.process_time()
        hits = caster.cast(origin, dirs, sensor.geometry.range_max_m)
        c1 = time.process_time()
        out = scene.run(np.tile(origin.astype(np.float32), (len(dirs), 1)), dirs.astype(np.float32), output=1)
        c2 = time.process_time()
        t_mj, t_em = t_mj + c1 - c0, t_em + c2 - c1
        dist = np.where(out["geomID"] >= 0, out["tfar"], np.inf)
        both = np.isfinite(dist) & np.isfinite(hits.dist_m)
        if both.any():
            worst = max(worst, float(np.abs(dist[both] - hits.dist_m[both]).max()))
    print(json.dumps({"scenario": scenario.name, "triangles": int(len(triangles)), "rays_per_frame": int(len(dirs)),
                      "mj_multiRay_cpu_ms_per_frame": round(1e3 * t_mj / args.frames, 3),
                      "embree_cpu_ms_per_frame": round(1e3 * t_em / args.frames, 3),
                      "embree_speedup": round(t_mj / t_em, 2), "max_hit_distance_difference_m": worst}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
