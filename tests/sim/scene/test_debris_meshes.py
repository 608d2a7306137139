"""Debris meshes: closed outward parts, exactly the configured box, on the bottom in the
scene, and the rays that hit them hit them where the mesh is (a ray from above meets the top
face at the mesh's height)."""

import numpy as np
import pytest

from scenarios.config.world import DEBRIS_TARGET_SHAPES, SeabedConfig, TargetConfig, WorldConfig
from scenarios.schema import Scenario
from sim.scene.debris_meshes import DEBRIS_SHAPES, debris_default_size_m
from sim.scene.target_meshes import debris_mesh
from sim.scene.world import build_world
from sim.sensors.raycast import MujocoRayCaster

FLOOR_M = 3.0


def test_config_and_mesh_module_agree_on_the_shapes():
    assert set(DEBRIS_TARGET_SHAPES) == set(DEBRIS_SHAPES)


@pytest.mark.parametrize("shape", DEBRIS_SHAPES)
def test_parts_are_closed_outward_and_fill_the_box(shape):
    size = tuple(1.3 * s for s in debris_default_size_m(shape))
    mesh = debris_mesh(shape, size)
    lo, hi = mesh.bounds
    assert np.allclose(hi - lo, size, atol=1e-9)
    assert np.allclose([lo[0], lo[1], hi[0], hi[1]], [-size[0] / 2, -size[1] / 2, size[0] / 2, size[1] / 2])
    assert hi[2] == pytest.approx(0.0, abs=1e-12) and lo[2] == pytest.approx(-size[2])
    parts = mesh.to_trimesh().split(only_watertight=False)
    assert all(p.is_watertight for p in parts)
    assert all(p.volume > 0 for p in parts)  # outward normals: positive signed volume per part
    assert mesh.volume > 0  # the project's own volume integral agrees on the orientation
    assert mesh.volume < np.prod(size)


def test_refuses_unknown_shapes_and_bad_sizes():
    with pytest.raises(ValueError, match="unknown debris shape"):
        debris_mesh("anchor", (1.0, 1.0, 1.0))
    with pytest.raises(ValueError, match="positive"):
        debris_mesh("can", (0.1, -0.05, 0.05))


def _world(targets):
    sc = Scenario(name="debris", world=WorldConfig(seabed=SeabedConfig(kind="plane", depth_m=FLOOR_M, extent_m=10.0),
                                                  targets=tuple(targets)))
    w = build_world(sc, with_vehicle=False)
    return w, MujocoRayCaster(w.model, w.data, w.geom_object_id, w.geom_reflectivity, exclude_body_id=-1)


def test_rays_from_above_meet_each_object_at_its_height():
    targets = [TargetConfig(name=s, shape=s, pos_ned=(1.0 * k, 0.0, FLOOR_M), size_m=debris_default_size_m(s),
                            class_name=s) for k, s in enumerate(DEBRIS_SHAPES)]
    world, caster = _world(targets)
    for obj, t in zip(world.objects, targets):
        mesh = debris_mesh(t.shape, t.size_m)
        # the vertical ray through the centroid of the highest face (from 1 m above the floor)
        # meets that face: at 1 m + the centroid's z (z < 0 up), within a few mm of the top
        tri = mesh.vertices[mesh.faces]
        normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        up = normal[:, 2] < -1e-12 * np.abs(normal).max()  # faces looking up (towards -z)
        cents = tri.mean(axis=1)
        top = cents[up][np.argmin(cents[up][:, 2])]
        origin = np.array([t.pos_ned[0] + top[0], top[1], FLOOR_M - 1.0])
        hit = caster.cast(origin, np.array([[0.0, 0.0, 1.0]]), 5.0)
        assert int(hit.object_id[0]) == obj.id, t.shape
        assert hit.dist_m[0] == pytest.approx(1.0 + top[2], abs=1e-4), t.shape
        assert top[2] == pytest.approx(-t.size_m[2], abs=0.1 * t.size_m[2]), t.shape


def test_a_standing_bottle_stands_on_the_floor():
    length = debris_default_size_m("bottle")[0]
    t = TargetConfig(name="b", shape="bottle", pos_ned=(0.0, 0.0, FLOOR_M - length / 2), rpy_deg=(0.0, 90.0, 0.0),
                     size_m=debris_default_size_m("bottle"))
    world, caster = _world([t])
    # straight down on its axis: the cap's top, one bottle length above the floor
    hit = caster.cast(np.array([-0.04, 0.0, FLOOR_M - 1.0]), np.array([[0.0, 0.0, 1.0]]), 5.0)
    assert int(hit.object_id[0]) == world.objects[0].id
    assert hit.dist_m[0] == pytest.approx(1.0 - length, abs=5e-3)
    assert world.objects[0].centroid_ned[2] < FLOOR_M
