"""MuJoCo ray caster against closed-form intersections (and the analytic caster)."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from autonomy.frames import quat_from_rot, rot_from_euler
from sim.sensors.analytic_caster import AnalyticBox, AnalyticCaster, AnalyticSphere
from sim.sensors.raycast import BACKGROUND_ID, NO_HIT_ID, MujocoRayCaster
from tests.support import random_dirs

DEPTH = 6.0
SPHERE_C, SPHERE_R = np.array([8.0, 1.0, 4.0]), 0.7
BOX_C, BOX_H = np.array([10.0, -3.0, 5.5]), np.array([0.6, 0.4, 0.5])
BOX_R = rot_from_euler(0.0, 0.0, 0.5)


def scene():
    spec = mujoco.MjSpec()
    spec.option.gravity = [0, 0, 0]
    spec.worldbody.add_geom(name="seabed", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[100, 100, 1],
                            pos=[0, 0, DEPTH], quat=[0, 1, 0, 0])  # normal -z (up in NED)
    spec.worldbody.add_geom(name="sphere", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[SPHERE_R, 0, 0],
                            pos=SPHERE_C.tolist())
    spec.worldbody.add_geom(name="box", type=mujoco.mjtGeom.mjGEOM_BOX, size=BOX_H.tolist(), pos=BOX_C.tolist(),
                            quat=quat_from_rot(BOX_R).tolist())
    hull = spec.worldbody.add_body(name="hull", pos=[0, 0, 2])
    hull.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.5, 0, 0])
    m = spec.compile()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    obj = np.array([BACKGROUND_ID, 0, 1, -3])
    refl = np.array([0.3, 0.9, 0.8, 0.0])
    hull_id = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "hull")
    return MujocoRayCaster(m, d, obj, refl, hull_id)


def test_a_seabed_plane_centred_beyond_the_range_is_still_hit():
    """The plane's centre lies 100 m away, the plane itself 4 m below: the ray must hit it at
    4 m whatever the range (MuJoCo 3.x culls geoms by centre distance, a plane's radius is 0),
    and a range shorter than the plane's distance is still a miss."""
    caster = scene()
    o = np.array([100.0, 0.0, 2.0])
    hits = caster.cast(o, np.array([[0.0, 0.0, 1.0], [-0.6, 0.0, 0.8]]), 20.0)
    assert hits.dist_m == pytest.approx([DEPTH - 2.0, (DEPTH - 2.0) / 0.8])
    assert list(hits.object_id) == [BACKGROUND_ID, BACKGROUND_ID]
    assert np.isinf(caster.cast(o, np.array([[0.0, 0.0, 1.0]]), 3.5).dist_m[0])


def analytic():
    return AnalyticCaster(DEPTH, 0.3, spheres=(AnalyticSphere(SPHERE_C, SPHERE_R, 0, 0.9),),
                          boxes=(AnalyticBox(BOX_C, BOX_H, 1, 0.8, BOX_R),))


def test_known_intersections():
    caster = scene()
    o = np.array([0.0, 0.0, 2.0])
    to_sphere = (SPHERE_C - o) / np.linalg.norm(SPHERE_C - o)
    dirs = np.array([[0.0, 0.0, 1.0], to_sphere, [0.0, 0.0, -1.0]])
    hits = caster.cast(o, dirs, 50.0)
    assert hits.dist_m[0] == pytest.approx(DEPTH - 2.0)  # through the excluded hull, onto the seabed
    assert hits.dist_m[1] == pytest.approx(np.linalg.norm(SPHERE_C - o) - SPHERE_R)
    assert np.isinf(hits.dist_m[2]) and hits.object_id[2] == NO_HIT_ID and hits.reflectivity[2] == 0.0
    assert list(hits.object_id[:2]) == [BACKGROUND_ID, 0]
    assert hits.reflectivity[:2] == pytest.approx([0.3, 0.9])
    assert hits.normal_ned[0] @ [0, 0, 1] == pytest.approx(-1.0)
    assert hits.normal_ned[1] == pytest.approx(-to_sphere)
    assert np.isinf(caster.cast(o, dirs[:1], 3.0).dist_m[0])  # beyond max range


def test_matches_analytic_caster_on_many_rays():
    caster, ref = scene(), analytic()
    o = np.array([0.0, 0.0, 2.0])
    dirs = random_dirs(3000)  # more than the initial buffer: buffers grow
    a, b = caster.cast(o, dirs, 60.0), ref.cast(o, dirs, 60.0)
    assert np.array_equal(a.object_id, b.object_id)
    fin = np.isfinite(b.dist_m)
    assert np.array_equal(np.isfinite(a.dist_m), fin) and fin.sum() > 1000
    assert np.allclose(a.dist_m[fin], b.dist_m[fin], atol=1e-6)
    assert np.allclose(np.abs(np.sum(a.normal_ned * b.normal_ned, axis=1))[fin], 1.0, atol=1e-6)
    assert np.allclose(a.reflectivity, b.reflectivity)
    assert {0, 1, BACKGROUND_ID} <= set(a.object_id.tolist())


def test_isolated_cast_ignores_occluders_and_restores_groups():
    caster, ref = scene(), analytic()
    groups = caster.model.geom_group.copy()
    o = np.array([0.0, 0.0, 2.0])
    dirs = random_dirs(2000, seed=1)
    for k in (0, 1):
        got = caster.cast_isolated(o, dirs, 60.0, k)
        want = ref.cast_isolated(o, dirs, 60.0, k)
        assert np.array_equal(np.isfinite(got), np.isfinite(want)) and np.isfinite(got).sum() > 0
        assert np.allclose(got[np.isfinite(got)], want[np.isfinite(want)], atol=1e-6)
    assert np.array_equal(caster.model.geom_group, groups)
    c, r = caster.object_bounding_sphere(0)
    assert c == pytest.approx(SPHERE_C) and r == pytest.approx(SPHERE_R)
    c, r = caster.object_bounding_sphere(1)
    assert r >= np.linalg.norm(BOX_H) - 1e-9


def test_bad_tables_rejected():
    caster = scene()
    with pytest.raises(ValueError, match="geom_object_id"):
        MujocoRayCaster(caster.model, caster.data, np.zeros(2), np.zeros(4), -1)


def test_bounding_sphere_follows_a_moved_object():
    """The sphere is kept while the object's geoms stay put and formed again once they move."""
    caster = scene()
    c0, r0 = caster.object_bounding_sphere(0)
    c0[:] = 0.0  # a caller's copy: changing it leaves the kept sphere alone
    c1, r1 = caster.object_bounding_sphere(0)
    assert c1 == pytest.approx(SPHERE_C) and r1 == r0
    gid = mujoco.mj_name2id(caster.model, mujoco.mjtObj.mjOBJ_GEOM, "sphere")
    caster.model.geom_pos[gid] = SPHERE_C + [1.5, -0.5, 0.25]
    mujoco.mj_forward(caster.model, caster.data)
    c2, r2 = caster.object_bounding_sphere(0)
    assert c2 == pytest.approx(SPHERE_C + [1.5, -0.5, 0.25]) and r2 == pytest.approx(SPHERE_R)


def test_embree_asked_without_embreex_warns_and_mujoco_casts(monkeypatch):
    from sim.sensors import embree_scene

    import sim.sensors.raycast as raycast

    monkeypatch.setattr(embree_scene, "available", lambda: False)
    raycast._warn_no_embree.cache_clear()  # once per process: this test's caster is the first
    base = scene()
    with pytest.warns(RuntimeWarning, match="embreex is not installed"):
        caster = MujocoRayCaster(base.model, base.data, base.geom_object_id, base.geom_reflectivity,
                                 base.exclude_body_id, backend="embree")
    o, dirs = np.array([0.0, 0.0, 2.0]), random_dirs(200)
    np.testing.assert_array_equal(caster.cast(o, dirs, 30.0).dist_m, base.cast(o, dirs, 30.0).dist_m)
    assert not caster.uses_embree
