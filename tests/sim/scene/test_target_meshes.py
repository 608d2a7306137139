"""The numpy target meshes are trimesh's, vertex for vertex and face for face (the oracle:
``trimesh.creation`` with its duplicate-vertex merge, and trimesh's mass properties), so scenes
compile and render as they did when trimesh built them."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from sim.scene import target_meshes as tm
def _trimesh_revolved(profile, sections=32) -> trimesh.Trimesh:
    mesh = trimesh.creation.revolve(profile, sections=sections)
    if mesh.volume < 0.0:
        mesh.invert()
    return mesh


def _reference(shape: str, p: dict) -> trimesh.Trimesh:
    """The meshes as the code before built them with trimesh."""
    if shape == "half_sphere":
        t = np.linspace(0.0, 0.5 * np.pi, 12)
        prof = np.vstack([[0.0, 0.0], np.c_[p["r"] * np.cos(t), -p["r"] * np.sin(t)]])
        prof[-1, 0] = 0.0
        return _trimesh_revolved(prof)
    if shape == "truncated_cone":
        prof = np.array([[0.0, 0.0], [p["r"], 0.0], [p["top"], -p["h"]], [0.0, -p["h"]]])
        return _trimesh_revolved(prof if p["top"] > 0.0 else prof[[0, 1, 3]])
    if shape == "cylinder":
        mesh = trimesh.creation.cylinder(radius=p["r"], height=p["h"], sections=32)
        mesh.apply_translation([0.0, 0.0, -0.5 * p["h"]])
        return mesh
    if shape == "box":
        mesh = trimesh.creation.box(extents=p["size"])
        mesh.apply_translation([0.0, 0.0, -0.5 * p["size"][2]])
        return mesh
    mesh = trimesh.creation.torus(major_radius=p["r"] - p["tube"], minor_radius=p["tube"], major_sections=32,
                                  minor_sections=12)
    mesh.apply_translation([0.0, 0.0, -p["tube"]])
    return mesh


def _ours(shape: str, p: dict) -> tm.TriangleMesh:
    return {"half_sphere": lambda: tm.half_sphere(p["r"]),
            "truncated_cone": lambda: tm.truncated_cone(p["r"], p["top"], p["h"]),
            "cylinder": lambda: tm.cylinder(p["r"], p["h"]), "box": lambda: tm.box(p["size"]),
            "tyre": lambda: tm.tyre(p["r"], p["tube"])}[shape]()


def _params(rng: np.random.Generator, shape: str) -> dict:
    r = float(rng.uniform(0.03, 1.5))  # debris rods to large targets
    return {"r": r, "top": float(r * rng.choice([0.0, rng.uniform(0.2, 0.6)])), "h": float(rng.uniform(0.05, 3.0)),
            "size": tuple(float(v) for v in rng.uniform(0.1, 1.5, 3)), "tube": float(r * rng.uniform(0.2, 0.35))}


SHAPES = ["half_sphere", "truncated_cone", "cylinder", "box", "tyre"]


@pytest.mark.parametrize("shape", SHAPES)
def test_meshes_equal_trimesh_bit_for_bit(shape):
    rng = np.random.default_rng(SHAPES.index(shape))
    for _ in range(25):
        p = _params(rng, shape)
        ref, ours = _reference(shape, p), _ours(shape, p)
        assert np.array_equal(ours.vertices, ref.vertices) and ours.vertices.dtype == np.float64
        assert np.array_equal(ours.faces, ref.faces)
        assert np.array_equal(ours.center_mass, ref.center_mass) and ours.volume == ref.volume > 0.0
        assert np.array_equal(ours.bounds, ref.bounds)
        assert ours.to_trimesh().is_watertight


def test_analytic_volume_and_centroid_of_a_box_and_a_half_sphere():
    b = tm.box((2.0, 1.0, 0.5))  # base at z = 0, top at z = -0.5 (NED: up is -z)
    assert b.volume == pytest.approx(1.0, rel=1e-12)
    np.testing.assert_allclose(b.center_mass, [0.0, 0.0, -0.25], atol=1e-12)
    h = tm.half_sphere(1.0)  # polygonal: a little under 2/3 pi, centroid near 3/8 r up
    assert h.volume == pytest.approx(2.0 / 3.0 * np.pi, rel=0.03)
    assert h.center_mass[2] == pytest.approx(-3.0 / 8.0, rel=0.03)


def test_unknown_shape_is_refused():
    from scenarios.config.world import TargetConfig

    cfg = TargetConfig(name="x", shape="box", pos_ned=(0.0, 0.0, 0.0)).model_copy(update={"shape": "blob"})
    with pytest.raises(ValueError, match="unknown target shape 'blob'"):
        tm.target_mesh(cfg)
