"""Watertight triangle meshes of seabed objects, in the object's NED-aligned local frame.

Every mesh has its base centre at the origin and extends *upwards*, i.e. towards negative
z (the local frame is NED-aligned: x north, y east, z down). Outward normals.

Built with numpy alone (no trimesh, whose import with scipy's costs a dataset worker about
0.4 s of CPU): the vertices, faces and their order are those ``trimesh.creation`` gives for the
same solids (``revolve`` with its default 32 sections and duplicate-vertex merge, ``box``,
``torus``), so compiled scenes and rendered frames are unchanged; the tests check both against
trimesh. :meth:`TriangleMesh.to_trimesh` gives a ``trimesh.Trimesh`` where one is wanted.
The marine-debris shapes (``bottle``, ``can``, ``chain``, ...) are handed on to
:mod:`sim.scene.debris_meshes`, which builds them with trimesh, imported only then.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from scenarios.config.world import DEBRIS_TARGET_SHAPES, TargetConfig
from sim.scene.triangle_mesh import TriangleMesh
from sim.scene.debris_meshes import debris_mesh as build

MERGE_DIGITS = 8  # vertices equal to 1e-8 m are one vertex (trimesh's ``tol.merge``)
# unit cube corners and faces in trimesh's order (``trimesh.creation.box``)
_BOX_VERTICES = np.array([[0, 0, 0], [0, 0, 1], [0, 1, 0], [0, 1, 1], [1, 0, 0], [1, 0, 1], [1, 1, 0], [1, 1, 1]],
                         dtype=np.float64)
_BOX_FACES = np.array([[1, 3, 0], [4, 1, 0], [0, 3, 2], [2, 4, 0], [1, 7, 3], [5, 1, 4], [5, 7, 1], [3, 7, 2],
                       [6, 4, 2], [2, 7, 6], [6, 5, 4], [7, 5, 6]], dtype=np.int64)


def _merge_duplicate_vertices(vertices: NDArray, faces: NDArray) -> TriangleMesh:
    """Merge vertices equal to ``MERGE_DIGITS`` decimals (first occurrence kept, in order of first
    occurrence among the referenced ones), as trimesh's ``merge_vertices`` does."""
    referenced = np.zeros(len(vertices), dtype=bool)
    referenced[faces] = True
    keys = np.round(vertices * 10.0**MERGE_DIGITS).astype(np.int64)[referenced]
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    remap = np.zeros(len(vertices), dtype=np.int64)
    remap[referenced] = rank[inverse.reshape(-1)]
    keep = np.nonzero(referenced)[0][first[order]]
    return TriangleMesh(np.ascontiguousarray(vertices[keep]), remap[faces])


def revolve(profile_rz: NDArray, sections: int = 32) -> TriangleMesh:
    """Surface swept by a 2D (radius, z) polyline turned once about the local z axis, as
    ``trimesh.creation.revolve`` builds it: ``sections`` slices, triangles of zero area dropped,
    coincident vertices (on the axis) merged."""
    line = np.asarray(profile_rz, dtype=np.float64)
    theta = np.linspace(0.0, 2.0 * np.pi, sections + 1)
    points = np.column_stack((np.cos(theta), np.sin(theta)))
    per = len(line)
    vertices = np.column_stack((np.tile(points, (1, per)).reshape((-1, 2)) * np.tile(line[:, 0], len(points)).reshape((-1, 1)),
                                np.tile(line[:, 1], len(points))))[:-per]
    quad = np.array([0, per, 1, 1, per, per + 1])
    single = np.tile(quad, per - 1).reshape((-1, 3)) + np.tile(np.arange(per - 1), (2, 1)).T.reshape((-1, 1))
    tri = vertices[single]
    area = np.sqrt((np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 1]) ** 2).sum(axis=1)) / 2.0
    single = single[area > 10.0**-MERGE_DIGITS]
    offset = np.tile(np.arange(sections) * per, (len(single), 1)).T.reshape((-1, 1))
    faces = (np.tile(single.ravel(), sections).reshape((-1, 3)) + offset) % len(vertices)
    return _merge_duplicate_vertices(vertices, faces)


def _revolve_outward(profile_rz: np.ndarray, sections: int) -> TriangleMesh:
    """Solid of revolution about the local z axis from a closed (radius, z) profile."""
    mesh = revolve(profile_rz, sections)
    return mesh.inverted() if mesh.volume < 0.0 else mesh


def half_sphere(radius_m: float, sections: int = 32, rings: int = 12) -> TriangleMesh:
    t = np.linspace(0.0, 0.5 * np.pi, rings)
    profile = np.vstack([[0.0, 0.0], np.c_[radius_m * np.cos(t), -radius_m * np.sin(t)]])
    profile[-1, 0] = 0.0
    return _revolve_outward(profile, sections)


def truncated_cone(base_radius_m: float, top_radius_m: float, height_m: float, sections: int = 32) -> TriangleMesh:
    profile = np.array([[0.0, 0.0], [base_radius_m, 0.0], [top_radius_m, -height_m], [0.0, -height_m]])
    if top_radius_m <= 0.0:
        profile = profile[[0, 1, 3]]
    return _revolve_outward(profile, sections)


def cylinder(radius_m: float, height_m: float, sections: int = 32) -> TriangleMesh:
    half = abs(float(height_m)) / 2.0
    mesh = revolve(np.array([[0.0, -half], [radius_m, -half], [radius_m, half], [0.0, half]]), sections)
    return mesh.translated((0.0, 0.0, -0.5 * height_m))


def box(size_m: tuple[float, float, float]) -> TriangleMesh:
    vertices = (_BOX_VERTICES - 0.5) * np.asarray(size_m, dtype=np.float64)
    return TriangleMesh(vertices, _BOX_FACES.copy()).translated((0.0, 0.0, -0.5 * size_m[2]))


def tyre(radius_m: float, tube_radius_m: float, sections: int = 32, tube_sections: int = 12) -> TriangleMesh:
    """Torus lying flat on the seabed; ``radius_m`` is the outer radius."""
    phi = np.linspace(0.0, 2.0 * np.pi, tube_sections + 1, endpoint=True)
    profile = np.column_stack((tube_radius_m * np.cos(phi), tube_radius_m * np.sin(phi))) + [radius_m - tube_radius_m, 0.0]
    return revolve(profile, sections).translated((0.0, 0.0, -tube_radius_m))


def debris_mesh(shape: str, size_m: tuple[float, float, float]) -> TriangleMesh:
    """The closed mesh of a marine-debris ``shape`` scaled to the box ``size_m`` (length, width,
    height, m), built with trimesh by :mod:`sim.scene.debris_meshes` (imported on first use, so
    scenes without debris import no trimesh); shared, read-only arrays.

    Raises:
        ValueError: not a debris shape, or a size that is not three positive lengths.
    """
    return build(shape, tuple(float(x) for x in size_m))


def target_mesh(cfg: TargetConfig) -> TriangleMesh:
    """The mesh for a target config, before its pose is applied.

    Shared: the same object's mesh is built once for placing it on the seabed and once for the
    scene, so recent meshes are kept (read-only arrays; callers transform copies).

    Raises:
        ValueError: an unknown ``cfg.shape``.
    """
    return _shape_mesh(cfg.shape, cfg.radius_m, cfg.top_radius_m, cfg.height_m, tuple(cfg.size_m), cfg.tube_radius_m)


@lru_cache(maxsize=128)
def _shape_mesh(shape: str, radius_m: float, top_radius_m: float, height_m: float,
                size_m: tuple[float, float, float], tube_radius_m: float) -> TriangleMesh:
    if shape == "half_sphere":
        mesh = half_sphere(radius_m)
    elif shape == "truncated_cone":
        mesh = truncated_cone(radius_m, top_radius_m, height_m)
    elif shape == "cylinder":
        mesh = cylinder(radius_m, height_m)
    elif shape == "box":
        mesh = box(size_m)
    elif shape == "tyre":
        mesh = tyre(radius_m, tube_radius_m)
    elif shape in DEBRIS_TARGET_SHAPES:
        return debris_mesh(shape, size_m)
    else:
        raise ValueError(f"unknown target shape {shape!r}")
    mesh.vertices.setflags(write=False)
    mesh.faces.setflags(write=False)
    return mesh
