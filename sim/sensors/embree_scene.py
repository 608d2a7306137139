"""Embree ray casting over a MuJoCo scene's triangles ([Wald2014]; ``embreex`` binary wheels).

:class:`TriangleScene` holds a bounding-volume hierarchy over the triangles of a set of MuJoCo
geoms at their current poses: meshes (their own triangles), boxes (12 triangles, exact) and
planes (two triangles :data:`PLANE_HALF_SIZE_M` across, far beyond any sonar's range). It
answers what ``mujoco.mj_multiRay`` answers: the geom hit first, the distance and the unit
surface normal (the triangle's, turned to face the ray, as a sonar reads it with ``|cos|``).
Embree works in float32: distances agree with MuJoCo's float64 casts to about 1e-5 m at tens
of metres (a sonar's range bin is 3 mm to 3 cm).

Used by :class:`sim.sensors.raycast.MujocoRayCaster` where ``embreex`` is installed and every
acoustic geom is a mesh, box or plane, for a scene whose geoms keep their poses: a pose change
rebuilds the hierarchy (a few ms), and a caster whose scene keeps moving returns to MuJoCo's
casts (:data:`MAX_REBUILDS`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sim.sensors.sonar.fused_passes import kernels

try:  # optional: x86-64 and macOS wheels; elsewhere MuJoCo casts every ray
    from embreex import mesh_construction as _mc
    from embreex import rtcore_scene as _rs
except ImportError:  # pragma: no cover - depends on the platform
    _mc = _rs = None

PLANE_HALF_SIZE_M = 2000.0  # a MuJoCo plane is infinite; two triangles this far each way stand for it
MAX_REBUILDS = 3  # pose changes after which a caster stops using Embree (a moving scene)
_BOX_CORNERS = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
_BOX_FACES = np.array([[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4],
                       [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]], dtype=np.int64)
_PLANE = np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]])
_PLANE_FACES = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64)


def available() -> bool:
    """Whether ``embreex`` could be imported."""
    return _rs is not None


def local_triangles(model, geom: int) -> tuple[NDArray[np.float64], NDArray[np.int64]] | None:
    """Vertices (V, 3) in the geom's frame and faces (F, 3) of one geom, or None for a type
    this module does not triangulate (spheres, cylinders, capsules, ellipsoids, height fields)."""
    import mujoco

    t = int(model.geom_type[geom])
    if t == mujoco.mjtGeom.mjGEOM_MESH:
        mid = int(model.geom_dataid[geom])
        va, nv = int(model.mesh_vertadr[mid]), int(model.mesh_vertnum[mid])
        fa, nf = int(model.mesh_faceadr[mid]), int(model.mesh_facenum[mid])
        return np.asarray(model.mesh_vert[va:va + nv], dtype=float), np.asarray(model.mesh_face[fa:fa + nf],
                                                                                 dtype=np.int64)
    if t == mujoco.mjtGeom.mjGEOM_BOX:
        return _BOX_CORNERS * np.asarray(model.geom_size[geom], dtype=float), _BOX_FACES
    if t == mujoco.mjtGeom.mjGEOM_PLANE:
        return _PLANE * PLANE_HALF_SIZE_M, _PLANE_FACES
    return None


class TriangleScene:
    """An Embree scene over ``geoms`` of a MuJoCo model (see the module).

    Args:
        model, data: the compiled scene (``data`` forwarded: geom poses are read from it).
        geoms: (G,) geom ids to include.

    Raises:
        ValueError: ``embreex`` is not installed, or a geom's type is not triangulated
            (:func:`local_triangles`).
    """

    def __init__(self, model, data, geoms: NDArray[np.integer]) -> None:
        if not available():
            raise ValueError("embreex is not installed")
        self.model, self.data = model, data
        self.geoms = np.asarray(geoms, dtype=np.int64).reshape(-1)
        parts = []
        for g in self.geoms:
            tri = local_triangles(model, int(g))
            if tri is None:
                raise ValueError(f"geom {int(g)}: type {int(model.geom_type[g])} is not triangulated")
            parts.append(tri)
        self._local = parts
        offsets = np.cumsum([0] + [len(f) for _, f in parts])
        self._tri_geom = np.repeat(self.geoms, np.diff(offsets)).astype(np.int32)
        self._scene = None
        self._pose_key: bytes | None = None
        self.rebuilds = 0

    def _poses(self) -> bytes:
        return self.data.geom_xpos[self.geoms].tobytes() + self.data.geom_xmat[self.geoms].tobytes()

    def current(self) -> bool:
        """Bring the hierarchy to the geoms' current poses; True when it had to be rebuilt."""
        key = self._poses()
        if key == self._pose_key:
            return False
        verts, faces, base = [], [], 0
        for g, (v, f) in zip(self.geoms, self._local):
            R = self.data.geom_xmat[g].reshape(3, 3)
            verts.append(v @ R.T + self.data.geom_xpos[g])
            faces.append(f + base)
            base += len(v)
        scene = _rs.EmbreeScene()
        if verts:
            _mc.TriangleMesh(scene, np.concatenate(verts).astype(np.float32),
                             np.concatenate(faces).astype(np.int32))
        rebuilt = self._pose_key is not None
        self._scene, self._pose_key = scene, key
        self.rebuilds += int(rebuilt)
        return rebuilt

    def cast(self, origin_ned: NDArray[np.float64], dirs_ned: NDArray[np.float64]
             ) -> tuple[NDArray[np.int32], NDArray[np.float64], NDArray[np.float64]]:
        """Cast unit ``dirs_ned`` (N, 3) from ``origin_ned`` (3,) at the scene as it stands
        (call :meth:`current` first): geom ids (N,) (-1: no hit), distances (N,) (-1 where
        none, as ``mj_multiRay``), unit normals (N, 3) facing the ray (zeros where none)."""
        n = int(dirs_ned.shape[0])
        if n == 0 or not len(self.geoms):
            return np.full(n, -1, np.int32), np.full(n, -1.0), np.zeros((n, 3))
        dirs = np.ascontiguousarray(dirs_ned, dtype=float).reshape(-1, 3)
        o32 = np.empty((n, 3), dtype=np.float32)
        o32[:] = np.asarray(origin_ned, dtype=np.float32).reshape(1, 3)
        out = self._scene.run(o32, dirs.astype(np.float32), output=1)
        geomid, dist, normal = np.empty(n, dtype=np.int32), np.empty(n), np.empty((n, 3))
        kernels().triangle_hits(out["primID"], out["tfar"], out["Ng"], dirs, self._tri_geom, geomid, dist, normal)
        return geomid, dist, normal
