"""Debris meshes: closed outward parts, exactly the configured box (base on z = 0, top at
z = -height), reached through ``target_mesh``; in a compiled MuJoCo scene a ray from above meets
each object at its mesh's height and reports the object's id; a pitched bottle stands on its base."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from autonomy.frames import rot_from_euler
from scenarios.config.world import DEBRIS_TARGET_SHAPES, SeabedConfig, TargetConfig, WorldConfig
from scenarios.schema import Scenario
from sim.scene.debris_meshes import DEBRIS_SHAPES, debris_default_size_m, debris_mesh, debris_real_size_m
from sim.scene.target_meshes import target_mesh
from sim.scene.world import build_world
from sim.sensors.raycast import MujocoRayCaster

FLOOR_M = 3.0
# shapes whose box centre is covered at full height (the hook's lies in its gape, the propeller's
# beside its hub: three blades put the box off the hub's axis)
FULL_AT_CENTRE = ("bottle", "can", "chain", "drink_carton", "shampoo_bottle", "valve")


def test_config_and_mesh_module_agree_on_the_shapes():
    assert DEBRIS_SHAPES == DEBRIS_TARGET_SHAPES
    assert set(DEBRIS_SHAPES) <= set(TargetConfig.model_fields["shape"].annotation.__args__)


@pytest.mark.parametrize("shape", DEBRIS_SHAPES)
def test_default_size_is_the_built_object_s_own_box(shape):
    """The defaults table is the solid's real proportions (rounded): the default size does not
    distort it."""
    np.testing.assert_allclose(debris_default_size_m(shape), debris_real_size_m(shape), rtol=0.01, atol=1e-3)


@pytest.mark.parametrize("scale", [(1.0, 1.0, 1.0), (1.3, 0.8, 1.1)])
@pytest.mark.parametrize("shape", DEBRIS_SHAPES)
def test_parts_are_closed_outward_and_fill_the_box(shape, scale):
    size = tuple(float(s * k) for s, k in zip(debris_default_size_m(shape), scale))
    cfg = TargetConfig(name="d", shape=shape, pos_ned=(0.0, 0.0, 0.0), size_m=size)
    mesh = target_mesh(cfg)
    assert mesh is debris_mesh(shape, size)  # dispatched, and cached by its parameters
    assert not mesh.vertices.flags.writeable and not mesh.faces.flags.writeable
    lo, hi = mesh.bounds
    np.testing.assert_allclose(hi - lo, size, atol=1e-6)
    np.testing.assert_allclose([lo[0], lo[1], hi[0], hi[1]], [-size[0] / 2, -size[1] / 2, size[0] / 2, size[1] / 2],
                               atol=1e-6)
    assert hi[2] == pytest.approx(0.0, abs=1e-9) and lo[2] == pytest.approx(-size[2], abs=1e-9)  # z down: up is -z
    parts = mesh.to_trimesh().split(only_watertight=False)
    assert len(parts) >= 1 and sum(len(p.faces) for p in parts) == len(mesh.faces)
    assert all(p.is_watertight and p.is_winding_consistent for p in parts)
    assert all(p.volume > 0.0 for p in parts)  # outward normals: positive signed volume per part
    volume = mesh._volume_moments()[0]  # the project's own integral agrees on the orientation
    assert 0.0 < volume < np.prod(size) and volume == pytest.approx(sum(p.volume for p in parts), rel=1e-9)


def test_refuses_unknown_shapes_and_bad_sizes():
    with pytest.raises(ValueError, match="unknown debris shape"):
        debris_mesh("anchor", (1.0, 1.0, 1.0))
    with pytest.raises(ValueError, match="positive"):
        debris_mesh("can", (0.1, -0.05, 0.05))
    with pytest.raises(KeyError):
        debris_default_size_m("tyre")


def _world(targets, with_vehicle=False):
    sc = Scenario(name="debris", world=WorldConfig(seabed=SeabedConfig(kind="plane", depth_m=FLOOR_M, extent_m=10.0),
                                                  targets=tuple(targets)))
    w = build_world(sc, with_vehicle=with_vehicle)
    return w, MujocoRayCaster(w.model, w.data, w.geom_object_id, w.geom_reflectivity, exclude_body_id=-1)


def _down(caster, north_east):
    """Vertical ray from 1 m above the floor: (object id, depth of the hit)."""
    hit = caster.cast(np.array([north_east[0], north_east[1], FLOOR_M - 1.0]), np.array([[0.0, 0.0, 1.0]]), 5.0)
    return int(hit.object_id[0]), FLOOR_M - 1.0 + float(hit.dist_m[0])


def _top_face_point(mesh) -> np.ndarray:
    """Centroid (local) of the up-facing face nearest the box centre among those within 1 mm of
    the top (a face's inside: no ray along an edge)."""
    tri = mesh.vertices[mesh.faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    cents = tri.mean(axis=1)
    top = (normal[:, 2] < 0.0) & (cents[:, 2] < mesh.bounds[0, 2] + 1e-3)
    return cents[top][np.argmin(np.hypot(cents[top][:, 0], cents[top][:, 1]))]


def test_each_shape_compiles_as_a_mesh_geom_and_rays_from_above_meet_its_top():
    targets = [TargetConfig(name=s, shape=s, pos_ned=(0.6 * k, 0.3, FLOOR_M), rpy_deg=(0.0, 0.0, 35.0 * k),
                            size_m=debris_default_size_m(s), class_name=s) for k, s in enumerate(DEBRIS_SHAPES)]
    world, caster = _world(targets)
    assert [o.shape for o in world.objects] == list(DEBRIS_SHAPES)
    for obj, t in zip(world.objects, targets):
        mesh = target_mesh(t)
        gid = obj.geom_id
        assert world.model.geom_type[gid] == mujoco.mjtGeom.mjGEOM_MESH and world.geom_object_id[gid] == obj.id
        assert world.model.mesh_facenum[world.model.geom_dataid[gid]] == len(mesh.faces)
        top_depth = FLOOR_M - t.size_m[2]
        assert obj.height_m == pytest.approx(t.size_m[2])
        R = rot_from_euler(*np.deg2rad(t.rpy_deg))
        # onto the object's centre (its base centre, the box's: yaw keeps it), a little off it: a
        # ray exactly along a ridge edge (the bottle's, the chain's) is a degenerate case
        oid, depth = _down(caster, np.asarray(t.pos_ned[:2]) + [0.0013, 0.0007])
        if t.shape in FULL_AT_CENTRE:
            assert oid == obj.id, t.shape
            assert depth == pytest.approx(top_depth, abs=5e-3), t.shape
        # onto the top face nearest the centre: the hit is that face, at the mesh's top height
        p = np.asarray(t.pos_ned) + R @ _top_face_point(mesh)
        oid, depth = _down(caster, p[:2])
        assert oid == obj.id, t.shape
        assert depth == pytest.approx(p[2], abs=1e-5), t.shape
        assert depth == pytest.approx(top_depth, abs=5e-3), t.shape
        oid, _ = _down(caster, (t.pos_ned[0] + 0.29, t.pos_ned[1]))  # 29 cm north: the floor
        assert oid != obj.id


def test_debris_collides_as_mesh_hulls_with_a_vehicle_in_the_scene():
    """With a vehicle the meshes get convex hulls for contacts; the scene still compiles."""
    targets = [TargetConfig(name=s, shape=s, pos_ned=(3.0 + 0.6 * k, 0.0, FLOOR_M), size_m=debris_default_size_m(s))
               for k, s in enumerate(DEBRIS_SHAPES)]
    world, _ = _world(targets, with_vehicle=True)
    gids = [o.geom_id for o in world.objects]
    assert all(world.model.geom_contype[g] for g in gids)
    assert all(world.model.mesh_graphadr[world.model.geom_dataid[g]] >= 0 for g in gids)


@pytest.mark.parametrize("yaw_deg", [0.0, 30.0])
def test_a_bottle_pitched_90_deg_stands_on_its_base(yaw_deg):
    from sim.dataset.randomization import resting_depth

    length, diameter, _ = debris_default_size_m("bottle")
    t = TargetConfig(name="b", shape="bottle", pos_ned=(0.5, -0.2, FLOOR_M - length / 2),
                     rpy_deg=(0.0, 90.0, yaw_deg), size_m=debris_default_size_m("bottle"))
    R = rot_from_euler(*np.deg2rad(t.rpy_deg))
    v = target_mesh(t).vertices @ R.T + np.asarray(t.pos_ned)
    assert v[:, 2].max() == pytest.approx(FLOOR_M, abs=1e-9)  # nothing below the floor
    assert v[:, 2].min() == pytest.approx(FLOOR_M - length, abs=1e-9)  # the cap's top, a length up
    foot = v[np.abs(v[:, 2] - FLOOR_M) < 1e-9]
    assert len(foot) >= 16  # a ring of base vertices on the floor, not a point: it stands
    base = np.asarray(t.pos_ned) + R @ [-length / 2, 0.0, -diameter / 2]  # the base end's centre, on the axis
    yaw = np.deg2rad(yaw_deg)
    np.testing.assert_allclose(base, [0.5 - diameter / 2 * np.cos(yaw), -0.2 - diameter / 2 * np.sin(yaw), FLOOR_M],
                               atol=1e-12)  # on the floor, half a diameter behind pos_ned
    axis = base[:2]
    np.testing.assert_allclose(foot[:, :2].mean(axis=0), axis, atol=1e-9)
    assert np.ptp(foot[:, 0]) > 0.5 * diameter and np.ptp(foot[:, 1]) > 0.5 * diameter
    at_zero = t.model_copy(update={"pos_ned": (t.pos_ned[0], t.pos_ned[1], 0.0)})
    assert resting_depth(at_zero, lambda n, e: np.full_like(n, FLOOR_M)) == pytest.approx(t.pos_ned[2], abs=1e-9)
    world, caster = _world([t])
    oid, depth = _down(caster, axis + 1e-4)  # straight down its axis: the flat top of the cap
    assert oid == world.objects[0].id
    assert depth == pytest.approx(FLOOR_M - length, abs=5e-3)
    assert world.objects[0].centroid_ned[2] < FLOOR_M - 0.3 * length


def test_a_debris_target_without_a_size_takes_its_kind_s_default_size():
    from scenarios import load_scenario
    from scenarios.config.world import DEBRIS_DEFAULT_SIZES_M

    scn = load_scenario("cssn_lawnmower", ["world.targets=[{name: B1, shape: bottle, pos_ned: [4.0, 12.0, 4.0]}, "
                                           "{name: V1, shape: valve, pos_ned: [6.0, 12.0, 4.0], size_m: [0.3, 0.2, 0.2]}, "
                                           "{name: X1, shape: box, pos_ned: [8.0, 12.0, 4.0]}]"])
    b, v, x = scn.world.targets
    assert b.size_m == DEBRIS_DEFAULT_SIZES_M["bottle"] == (0.25, 0.08, 0.08)
    assert v.size_m == (0.3, 0.2, 0.2) and x.size_m == (1.0, 0.5, 0.5)
