"""World builder: seabed geometry, walls and targets checked by ray casts against analytic depths."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from scenarios import load_scenario
from sim.sensors.raycast import BACKGROUND_ID
from sim.scene.world import build_world


def _cast(world, origin, dirs):
    dirs = np.asarray(dirs, dtype=float).reshape(-1, 3)
    dirs = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    n = len(dirs)
    gid = np.zeros(n, np.int32)
    dist = np.zeros(n)
    mujoco.mj_multiRay(world.model, world.data, np.asarray(origin, float), dirs.ravel(), world.acoustic_geomgroup,
                       1, -1, gid, dist, None, n, 1000.0)
    return gid, dist


def test_flat_seabed_depth_and_targets_on_it():
    world = build_world(load_scenario("cssn_lawnmower"), with_vehicle=False)
    gid, dist = _cast(world, [3.0, 3.0, 1.0], [0, 0, 1])
    assert world.geom_object_id[gid[0]] == BACKGROUND_ID
    assert dist[0] == pytest.approx(3.0, abs=1e-9)
    # A vertical ray onto each half-sphere's apex hits the object at depth 4 - r.
    for obj in world.objects:
        # (slightly off the axis: a ray exactly through the apex vertex is a degenerate case)
        top = obj.base_ned + [0.013, 0.007, 0.0]
        gid, dist = _cast(world, top - [0, 0, 3.0], [0, 0, 1])
        assert world.geom_object_id[gid[0]] == obj.id
        assert 1.0 + dist[0] == pytest.approx(3.0 + 0.5, abs=0.01)  # hits apex at depth 3.5
        # half-sphere centroid is 3r/8 above its base
        assert obj.centroid_ned[2] == pytest.approx(4.0 - 3 * 0.5 / 8, abs=0.01)


# a survey that fits the small seabed patches below (20-30 m squares centred at (-4, 17))
SMALL_SURVEY = ("autonomy.guidance.survey.origin_ne_m=[-8, 10]", "autonomy.guidance.survey.length_m=10",
                "autonomy.guidance.survey.width_m=4")


@pytest.mark.parametrize("slope_deg,az_deg", [(5.0, 0.0), (10.0, 90.0)])
def test_sloped_seabed_matches_analytic_plane(slope_deg, az_deg):
    scn = load_scenario("cssn_lawnmower", [f"world.seabed.kind=slope", f"world.seabed.slope_deg={slope_deg}",
                                           f"world.seabed.slope_azimuth_deg={az_deg}", "world.basin.shape=none",
                                           "autonomy.guidance.survey.altitude_m=0.5",
                                           # the deep end of the slope: the survey's abort limit follows it
                                           "autonomy.guidance.mission.safe_depth_max_m=10",
                                           "world.targets=[]"])
    world = build_world(scn, with_vehicle=False)
    cn, ce = scn.world.seabed.center_ne_m
    for dn, de in [(0, 0), (10, 0), (0, 10), (-12, 7)]:
        n, e = cn + dn, ce + de
        _, dist = _cast(world, [n, e, 0.0], [0, 0, 1])
        along = dn * np.cos(np.deg2rad(az_deg)) + de * np.sin(np.deg2rad(az_deg))
        assert dist[0] == pytest.approx(4.0 + np.tan(np.deg2rad(slope_deg)) * along, abs=1e-6)


@pytest.mark.parametrize("kind", ["rough", "ripple"])
def test_terrain_mesh_raycast_matches_depth_lookup(kind):
    scn = load_scenario("cssn_lawnmower", [f"world.seabed.kind={kind}", "world.seabed.extent_m=30",
                                           "world.seabed.mesh_resolution_m=0.5", "world.seabed.roughness_m=0.1",
                                           "world.seabed.ripple_amplitude_m=0.2", "world.basin.shape=none",
                                           "vehicle.initial_pos_ned=[-4, 17, 0.3]", *SMALL_SURVEY,
                                           "world.targets=[]"])
    world = build_world(scn, with_vehicle=False)
    rng = np.random.default_rng(0)
    cn, ce = scn.world.seabed.center_ne_m
    pts = np.c_[cn + rng.uniform(-10, 10, 20), ce + rng.uniform(-10, 10, 20)]
    for n, e in pts:
        _, dist = _cast(world, [n, e, 0.0], [0, 0, 1])
        # bilinear interpolation of a triangulated grid differs from the mesh by < curvature * h^2
        assert dist[0] == pytest.approx(float(world.seabed.depth_at(n, e)), abs=0.03)
    relief = world.seabed.depth_grid_m - 4.0
    assert relief.std() > 0.05


def test_rough_seabed_is_seeded():
    over = ["world.seabed.kind=rough", "world.seabed.extent_m=20", "vehicle.initial_pos_ned=[-4, 17, 0.3]", *SMALL_SURVEY]
    a = build_world(load_scenario("cssn_lawnmower", over), with_vehicle=False).seabed.depth_grid_m
    b = build_world(load_scenario("cssn_lawnmower", over), with_vehicle=False).seabed.depth_grid_m
    c = build_world(load_scenario("cssn_lawnmower", over + ["seed=1"]), with_vehicle=False).seabed.depth_grid_m
    assert np.array_equal(a, b) and not np.array_equal(a, c)


def test_all_target_shapes_and_walls():
    shapes = ["tyre", "box", "truncated_cone", "cylinder", "half_sphere"]
    over = ["world.basin.shape=circular", "world.basin.radius_m=25"] + [
        f"world.targets.{i}.shape={s}" for i, s in enumerate(shapes)]
    world = build_world(load_scenario("cssn_lawnmower", over), with_vehicle=False)
    assert [o.shape for o in world.objects][:5] == shapes
    for obj in world.objects:
        gid, dist = _cast(world, obj.centroid_ned + [0.013, 0.007, -3.0], [0, 0, 1])
        if obj.shape == "tyre":  # the ray passes through the hole onto the seabed
            assert world.geom_object_id[gid[0]] == BACKGROUND_ID
        else:
            assert world.geom_object_id[gid[0]] == obj.id
            assert 4.0 - (obj.centroid_ned[2] - 3.0 + dist[0]) == pytest.approx(obj.height_m, abs=0.02)
    # A horizontal ray from the basin centre hits the circular wall at ~radius.
    gid, dist = _cast(world, [-4.0, 17.0, 2.0], [[1, 0, 0], [0, 1, 0], [-1, -1, 0]])
    assert np.all(world.geom_object_id[gid] == BACKGROUND_ID)
    assert np.allclose(dist, 25.0, atol=0.1)


def test_scene_without_vehicle_builds_no_target_hulls_and_rays_see_the_same_scene():
    """Without a vehicle nothing can touch a target, so its mesh gets no convex hull; the reference
    is the same spec recompiled with the targets colliding (hulls built): vertices, poses, each
    mesh's bounding-volume tree and the hits of rays fanned at every target are identical."""
    from scenarios.config.world import WorldConfig
    from scenarios.schema import Scenario
    from sim.dataset.generate import scene_spec
    from sim.dataset.randomization import WIDE_RANDOMIZATION

    spec = scene_spec(0, 3, WIDE_RANDOMIZATION)  # rippled terrain mesh, four targets
    scenario = Scenario(name="hulls", seed=spec.world_seed,
                        world=WorldConfig(seabed=spec.seabed, basin=spec.basin, targets=spec.targets))
    world = build_world(scenario, with_vehicle=False)
    targets = [o.geom_id for o in world.objects]
    assert len(targets) == 4 and all(world.model.mesh_graphadr[world.model.geom_dataid[g]] == -1 for g in targets)
    for g in world.spec.geoms:
        if g.name.startswith("target:"):
            g.contype = g.conaffinity = 1
    ref = world.spec.compile()
    ref_data = mujoco.MjData(ref)
    mujoco.mj_forward(ref, ref_data)
    assert all(ref.mesh_graphadr[ref.geom_dataid[g]] >= 0 for g in targets)  # the reference has hulls
    m = world.model
    for field in ("mesh_vert", "mesh_face", "mesh_pos", "mesh_quat", "geom_pos", "geom_quat", "geom_aabb", "geom_rbound"):
        assert np.array_equal(getattr(m, field), getattr(ref, field)), field
    for k in range(m.nmesh):
        a, b, num = m.mesh_bvhadr[k], ref.mesh_bvhadr[k], m.mesh_bvhnum[k]
        assert num == ref.mesh_bvhnum[k] and np.array_equal(m.bvh_aabb[a:a + num], ref.bvh_aabb[b:b + num])
    rng = np.random.default_rng(0)
    origin = np.array(spec.poses[0].pos_ned)
    for obj in world.objects:
        dirs = (obj.centroid_ned - origin) + rng.normal(0.0, 0.5, (2000, 3))
        hits = _cast(world, origin, dirs)
        ref_world = type(world)(world.spec, ref, ref_data, world.seabed, world.objects, world.geom_object_id,
                                world.geom_reflectivity, world.vehicle_body_id)
        ref_hits = _cast(ref_world, origin, dirs)
        assert np.array_equal(hits[0], ref_hits[0]) and np.array_equal(hits[1], ref_hits[1])
        assert np.any(hits[0] == obj.geom_id)  # the fan does reach the target
