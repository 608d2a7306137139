"""Embree's casts (``physics.ray_caster: embree``) against closed-form intersections, MuJoCo's
casts on the shipped scene, and the fall-backs to MuJoCo (untriangulated geoms, a moving scene).

Needs ``embreex`` (the ``fast`` extra); skipped where it is not installed."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from autonomy.frames import quat_from_rot, rot_from_euler
from scenarios.load import load_scenario
from sim.scene.world import build_world
from sim.sensors import embree_scene
from sim.sensors.analytic_caster import AnalyticBox, AnalyticCaster
from sim.sensors.raycast import BACKGROUND_ID, MujocoRayCaster
from tests.support import random_dirs

pytestmark = pytest.mark.skipif(not embree_scene.available(), reason="embreex is not installed (pip install "
                                "'auvsim[fast]')")

DEPTH = 6.0
BOX_C, BOX_H = np.array([10.0, -3.0, 5.5]), np.array([0.6, 0.4, 0.5])
BOX_R = rot_from_euler(0.1, 0.0, 0.5)


def box_scene(*, sphere: bool = False, backend: str = "embree") -> MujocoRayCaster:
    spec = mujoco.MjSpec()
    spec.option.gravity = [0, 0, 0]
    spec.worldbody.add_geom(name="seabed", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[100, 100, 1],
                            pos=[0, 0, DEPTH], quat=[0, 1, 0, 0])
    body = spec.worldbody.add_body(name="box", pos=BOX_C.tolist(), quat=quat_from_rot(BOX_R).tolist(), mocap=True)
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=BOX_H.tolist())
    if sphere:
        spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.5, 0, 0], pos=[8.0, 2.0, 4.0])
    hull = spec.worldbody.add_body(name="hull", pos=[0, 0, 2])
    hull.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.5, 0.2, 0.2])
    m = spec.compile()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    obj = np.array([BACKGROUND_ID, 0] + ([1] if sphere else []) + [-3])
    refl = np.array([0.3, 0.8] + ([0.9] if sphere else []) + [0.0])
    return MujocoRayCaster(m, d, obj, refl, mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "hull"), backend=backend)


def test_box_and_plane_match_closed_form_intersections():
    caster = box_scene()
    exact = AnalyticCaster(DEPTH, 0.3, boxes=(AnalyticBox(BOX_C, BOX_H, 0, 0.8, BOX_R),))
    o = np.array([0.0, 0.0, 2.0])
    dirs = random_dirs(4000)
    dirs[:2000] = BOX_C - o + np.random.default_rng(1).uniform(-0.6, 0.6, (2000, 3))  # many at the box
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    got, ref = caster.cast(o, dirs, 50.0), exact.cast(o, dirs, 50.0)
    assert caster.uses_embree
    hit = np.isfinite(ref.dist_m)
    assert np.array_equal(np.isfinite(got.dist_m), hit)
    assert np.abs(got.dist_m[hit] - ref.dist_m[hit]).max() < 2e-5  # float32 BVH, metres
    np.testing.assert_array_equal(got.object_id[hit], ref.object_id[hit])
    dots = np.einsum("ij,ij->i", got.normal_ned[hit], ref.normal_ned[hit])
    assert np.abs(dots).min() > 1.0 - 1e-6
    # normals face the ray (what mj_multiRay returns for a surface seen from outside)
    assert np.all(np.einsum("ij,ij->i", got.normal_ned[hit], dirs[hit]) < 0.0)


def test_shipped_scene_matches_mujoco_casts():
    w = build_world(load_scenario("cssn_lawnmower"))
    args = (w.model, w.data, w.geom_object_id, w.geom_reflectivity, w.vehicle_body_id)
    fast, ref = MujocoRayCaster(*args, backend="embree"), MujocoRayCaster(*args, backend="mujoco")
    o = np.array([8.0, 5.0, 3.0])
    d = np.random.default_rng(2).normal(size=(20000, 3))
    d[:, 2] = np.abs(d[:, 2])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    a, b = fast.cast(o, d, 40.0), ref.cast(o, d, 40.0)
    assert fast.uses_embree and not ref.uses_embree
    hit = np.isfinite(b.dist_m)
    assert hit.sum() > 10000
    assert np.mean(np.isfinite(a.dist_m) == hit) > 0.9999  # a ray grazing an edge may differ
    both = hit & np.isfinite(a.dist_m)
    assert np.abs(a.dist_m[both] - b.dist_m[both]).max() < 1e-4
    assert np.mean(a.object_id[both] == b.object_id[both]) > 0.9999
    np.testing.assert_array_equal(a.reflectivity[both & (a.object_id == b.object_id)],
                                  b.reflectivity[both & (a.object_id == b.object_id)])
    for k in {int(o.id) for o in w.objects}:
        at = np.asarray(w.objects[k].centroid_ned) - o
        rays = at / np.linalg.norm(at) + np.random.default_rng(k).normal(scale=0.01, size=(300, 3))
        rays /= np.linalg.norm(rays, axis=1, keepdims=True)
        x, y = fast.cast_isolated(o, rays, 40.0, k), ref.cast_isolated(o, rays, 40.0, k)
        assert np.isfinite(y).sum() > 0
        assert np.mean(np.isfinite(x) == np.isfinite(y)) > 0.99
        ok = np.isfinite(x) & np.isfinite(y)
        assert np.abs(x[ok] - y[ok]).max() < 1e-4


def test_untriangulated_geoms_and_moving_scenes_fall_back_to_mujoco():
    with_sphere = box_scene(sphere=True)
    o, dirs = np.array([0.0, 0.0, 2.0]), random_dirs(500)
    got = with_sphere.cast(o, dirs, 50.0)
    assert not with_sphere.uses_embree
    ref = box_scene(sphere=True, backend="mujoco").cast(o, dirs, 50.0)
    np.testing.assert_array_equal(got.dist_m, ref.dist_m)

    caster = box_scene()
    exact_at = []
    for k in range(embree_scene.MAX_REBUILDS + 2):
        caster.data.mocap_pos[0] = BOX_C + [0.0, 0.3 * k, 0.0]
        mujoco.mj_forward(caster.model, caster.data)
        hits = caster.cast(o, dirs, 50.0)
        exact_at.append((caster.uses_embree, hits))
        moved = AnalyticCaster(DEPTH, 0.3, boxes=(AnalyticBox(BOX_C + [0.0, 0.3 * k, 0.0], BOX_H, 0, 0.8, BOX_R),))
        ref = moved.cast(o, dirs, 50.0)
        hit = np.isfinite(ref.dist_m)
        assert np.array_equal(np.isfinite(hits.dist_m), hit)  # every pose is cast where it is
        assert np.abs(hits.dist_m[hit] - ref.dist_m[hit]).max() < 2e-5
    assert [u for u, _ in exact_at] == [True] * (embree_scene.MAX_REBUILDS + 1) + [False]


def test_bad_backend_is_refused():
    with pytest.raises(ValueError, match="backend"):
        box_scene(backend="optix")
