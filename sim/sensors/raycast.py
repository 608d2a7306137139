"""Ray casting behind a small interface.

Sensors that cast rays (FLS, DVL beams, altimeter, later MSIS) take a :class:`RayCaster`.
:class:`MujocoRayCaster` wraps ``mujoco.mj_multiRay`` on the compiled scene; tests use
the analytic casters in :mod:`sim.sensors.analytic_caster`.
"""

from __future__ import annotations

import functools
import warnings
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from sim.sensors import embree_scene
from sim.sensors.embree_scene import TriangleScene

FloatArray = NDArray[np.float64]
BACKGROUND_ID = -1  # object id of seabed, walls and anything not a scene object


@dataclass(frozen=True, slots=True)
class RayHits:
    """Result of casting N rays.

    Attributes:
        dist_m: (N,) distance to the first hit, ``inf`` where nothing was hit in range.
        normal_ned: (N, 3) unit surface normal at the hit (zeros where no hit).
        reflectivity: (N,) acoustic reflectivity of the surface hit, in [0, 1] (0 if none).
        object_id: (N,) scene-object id hit, :data:`BACKGROUND_ID` for seabed/walls,
            and -2 where nothing was hit.
    """

    dist_m: FloatArray
    normal_ned: FloatArray
    reflectivity: FloatArray
    object_id: NDArray[np.int64]


class RayCaster(Protocol):
    """Anything that can cast rays from one origin into the scene."""

    def cast(self, origin_ned: FloatArray, dirs_ned: FloatArray, max_range_m: float) -> RayHits:
        """Cast rays from ``origin_ned`` (3,) along unit ``dirs_ned`` (N, 3)."""
        ...


class IsolatingRayCaster(RayCaster, Protocol):
    """A caster that can also cast against one scene object alone (occlusion ground truth)."""

    def cast_isolated(self, origin_ned: FloatArray, dirs_ned: FloatArray, max_range_m: float,
                      object_id: int) -> FloatArray:
        """(N,) distance to object ``object_id`` as if it were alone in the scene (``inf`` if missed)."""
        ...

    def object_bounding_sphere(self, object_id: int) -> tuple[FloatArray, float]:
        """Centre (3,) NED and radius (m) of a sphere enclosing the object."""
        ...


NO_HIT_ID = -2  # object id reported where a ray hits nothing


@functools.cache
def _warn_no_embree() -> None:
    """Say once per process (every mission, worker and env builds a caster) that Embree was
    asked for and MuJoCo casts."""
    warnings.warn("physics.ray_caster: embree asked for, but embreex is not installed (pip install "
                  "'auvsim[fast]', x86-64 wheels): MuJoCo casts the rays", RuntimeWarning, stacklevel=3)


class MujocoRayCaster:
    """:class:`RayCaster` over a compiled MuJoCo scene with ``mujoco.mj_multiRay``.

    Args:
        model, data: the compiled scene (``data`` must be forwarded for geom poses).
        geom_object_id: (ngeom,) scene-object id per geom (``BACKGROUND_ID`` for seabed and
            walls; anything below ``BACKGROUND_ID`` marks geoms that are not acoustic).
        geom_reflectivity: (ngeom,) acoustic reflectivity per geom in [0, 1].
        exclude_body_id: body whose geoms rays ignore (the hull); -1 for none.
        geomgroup: (6,) ``mj_multiRay`` group mask; default: the groups of the acoustic geoms.
        backend: ``"mujoco"`` (default): ``mj_multiRay`` always; ``"embree"``: Embree
            (:mod:`sim.sensors.embree_scene`) where ``embreex`` is installed, every geom the rays
            may meet is a mesh, box or plane and the scene stays still, else ``mj_multiRay``
            (the scenario's ``physics.ray_caster``). Asking for Embree without ``embreex``
            warns (``RuntimeWarning``).
            :meth:`exit_distances` and :meth:`object_bounding_sphere` are MuJoCo's either way.

    Attributes:
        backend: the backend asked for; :attr:`uses_embree` whether the last cast used Embree.
    """

    def __init__(self, model, data, geom_object_id: NDArray[np.integer], geom_reflectivity: FloatArray,
                 exclude_body_id: int, geomgroup: NDArray[np.uint8] | None = None, *,
                 backend: str = "mujoco") -> None:
        import mujoco

        if backend not in ("mujoco", "embree"):
            raise ValueError(f"backend must be 'mujoco' or 'embree', got {backend!r}")
        self.backend = backend
        if backend == "embree" and not embree_scene.available():
            _warn_no_embree()
        self.uses_embree = False
        # Embree scenes: None for every cast geom, an object id for that object alone; False: MuJoCo casts
        self._embree: dict[int | None, TriangleScene | bool] = {}

        self._mj = mujoco
        self.model = model
        self.data = data
        self.geom_object_id = np.asarray(geom_object_id, dtype=np.int64)
        self.geom_reflectivity = np.asarray(geom_reflectivity, dtype=float)
        if self.geom_object_id.shape != (model.ngeom,) or self.geom_reflectivity.shape != (model.ngeom,):
            raise ValueError(f"geom_object_id and geom_reflectivity must have shape ({model.ngeom},), got "
                             f"{self.geom_object_id.shape} and {self.geom_reflectivity.shape}")
        self.exclude_body_id = int(exclude_body_id)
        if geomgroup is None:
            geomgroup = np.zeros(6, dtype=np.uint8)
            acoustic = self.geom_object_id >= BACKGROUND_ID
            geomgroup[np.unique(np.clip(model.geom_group[acoustic], 0, 5))] = 1
        self.geomgroup = np.ascontiguousarray(geomgroup, dtype=np.uint8)
        # MuJoCo 3.x culls a geom whose centre is farther than the cutoff less its bounding radius,
        # and a plane's radius is 0: a seabed plane centred farther away than the range would be
        # missed by every ray. The plane centres raise the cutoff; hits beyond the range are
        # dropped afterwards either way, so the results do not depend on the version.
        planes = np.flatnonzero(np.asarray(model.geom_type) == mujoco.mjtGeom.mjGEOM_PLANE)
        self._plane_geoms = planes[self.geomgroup[np.clip(model.geom_group[planes], 0, 5)] > 0]
        # lookup tables with a trailing "no hit" entry, indexed by geom id (-1 -> last)
        self._obj_lut = np.append(self.geom_object_id, NO_HIT_ID)
        self._refl_lut = np.append(self.geom_reflectivity, 0.0)
        self._object_geoms = {int(k): np.flatnonzero(self.geom_object_id == k)
                              for k in np.unique(self.geom_object_id[self.geom_object_id >= 0])}
        self._isolated_group = np.zeros(6, dtype=np.uint8)
        self._isolated_group[5] = 1
        self._spheres: dict[int, tuple[bytes, FloatArray, float]] = {}  # id -> (geom poses, centre, radius)

    def _embree_scene(self, key: int | None) -> TriangleScene | None:
        """The Embree scene of every cast geom (``key`` None) or of object ``key`` alone, at the
        geoms' current poses; None where MuJoCo casts (see ``backend``)."""
        if self.backend != "embree" or not embree_scene.available():
            return None
        scene = self._embree.get(key)
        if scene is None:
            if key is None:
                groups = self.geomgroup[np.clip(self.model.geom_group, 0, 5)] > 0
                geoms = np.flatnonzero(groups & (np.asarray(self.model.geom_bodyid) != self.exclude_body_id))
            else:
                geoms = self._object_geoms.get(int(key), np.zeros(0, np.int64))
            try:
                scene = TriangleScene(self.model, self.data, geoms)
            except ValueError:  # a sphere, cylinder, height field...: MuJoCo casts
                scene = False
            self._embree[key] = scene
        if scene is False:
            return None
        scene.current()
        if scene.rebuilds > embree_scene.MAX_REBUILDS:  # a moving scene: MuJoCo from now on
            self._embree[key] = False
            return None
        return scene

    def _raw(self, origin_ned: FloatArray, dirs_ned: FloatArray, max_range_m: float, geomgroup: NDArray[np.uint8],
             body_exclude: int) -> tuple[NDArray[np.int32], FloatArray, FloatArray]:
        """``mj_multiRay`` (or Embree's casts, see ``backend``) into fresh result arrays: geom
        ids (N,), distances (N,), normals (N, 3)."""
        if geomgroup is self.geomgroup and body_exclude == self.exclude_body_id:
            scene = self._embree_scene(None)
            self.uses_embree = scene is not None
            if scene is not None:
                return scene.cast(origin_ned, np.ascontiguousarray(dirs_ned, dtype=float).reshape(-1, 3))
        n = int(dirs_ned.shape[0])
        geomid, dist, normal = np.empty(n, dtype=np.int32), np.empty(n), np.empty((n, 3))
        origin = np.ascontiguousarray(origin_ned, dtype=float).reshape(3)
        cutoff = float(max_range_m)
        if self._plane_geoms.size and geomgroup is self.geomgroup:
            centre_m = np.sqrt(np.max(np.sum((self.data.geom_xpos[self._plane_geoms] - origin) ** 2, axis=1)))
            cutoff = max(cutoff, float(centre_m) + 1.0)
        self._mj.mj_multiRay(self.model, self.data, origin, np.ascontiguousarray(dirs_ned, dtype=float).reshape(-1),
                             geomgroup, 1, body_exclude, geomid, dist, normal.reshape(-1), n, cutoff)
        return geomid, dist, normal

    def cast(self, origin_ned: FloatArray, dirs_ned: FloatArray, max_range_m: float) -> RayHits:
        """Cast unit ``dirs_ned`` (N, 3) from ``origin_ned`` (3,); hits beyond ``max_range_m`` are misses."""
        geomid, dist, normal = self._raw(origin_ned, dirs_ned, max_range_m, self.geomgroup, self.exclude_body_id)
        gid = geomid.astype(np.intp)
        miss = (gid < 0) | ~(dist <= max_range_m)
        dist[miss] = np.inf
        gid[miss] = -1
        normal[miss] = 0.0
        return RayHits(dist_m=dist, normal_ned=normal, reflectivity=self._refl_lut[gid],
                       object_id=self._obj_lut[gid])

    def cast_isolated(self, origin_ned: FloatArray, dirs_ned: FloatArray, max_range_m: float,
                      object_id: int) -> FloatArray:
        """(N,) distance to object ``object_id``'s geoms alone (``inf`` where missed).

        Temporarily moves the object's geoms into group 5 and everything else out of it.
        """
        geoms = self._object_geoms.get(int(object_id))
        if geoms is None or len(dirs_ned) == 0:
            return np.full(len(dirs_ned), np.inf)
        scene = self._embree_scene(int(object_id))
        if scene is not None:
            _, dist, _ = scene.cast(origin_ned, np.ascontiguousarray(dirs_ned, dtype=float).reshape(-1, 3))
            d = np.where(dist >= 0.0, dist, np.inf)
            d[d > max_range_m] = np.inf
            return d
        saved = self.model.geom_group.copy()
        try:
            self.model.geom_group[:] = 0
            self.model.geom_group[geoms] = 5
            geomid, dist, _ = self._raw(origin_ned, dirs_ned, max_range_m, self._isolated_group, -1)
        finally:
            self.model.geom_group[:] = saved
        d = np.where(geomid >= 0, dist, np.inf)
        d[d > max_range_m] = np.inf
        return d

    def exit_distances(self, points_ned: FloatArray, dirs_ned: FloatArray, object_ids: NDArray[np.int64]
                       ) -> FloatArray:
        """Distance (N,) from each ``points_ned`` (N, 3, NED m, on or inside object
        ``object_ids[i]``) along its unit ``dirs_ned`` to where the ray leaves that object, its
        far wall (``inf`` where the ray does not meet it).

        Cast backwards from beyond the object's bounding sphere against the object alone (its
        geoms in a group of their own, as :meth:`cast_isolated`), which works for meshes and
        primitives alike. One ``mj_ray`` per ray: meant for the rays on objects, not a fan.
        Used by the back-wall echoes of :mod:`sim.sensors.sonar.image_formation`.
        """
        pts = np.ascontiguousarray(points_ned, dtype=float).reshape(-1, 3)
        dirs = np.ascontiguousarray(dirs_ned, dtype=float).reshape(-1, 3)
        ids = np.asarray(object_ids, dtype=np.int64).reshape(-1)
        out = np.full(pts.shape[0], np.inf)
        geomid = np.zeros(1, dtype=np.int32)
        saved = self.model.geom_group.copy()
        try:
            for k in np.unique(ids):
                geoms = self._object_geoms.get(int(k))
                if geoms is None:
                    continue
                centre, radius = self.object_bounding_sphere(int(k))
                self.model.geom_group[:] = 0
                self.model.geom_group[geoms] = 5
                for i in np.flatnonzero(ids == k):
                    # beyond the sphere along the ray, looking back
                    span = 2.0 * radius + float(np.linalg.norm(pts[i] - centre))
                    back = pts[i] + span * dirs[i]
                    x = self._mj.mj_ray(self.model, self.data, back, -dirs[i], self._isolated_group, 1, -1, geomid)
                    if 0.0 <= x <= span and geomid[0] >= 0:
                        out[i] = span - x
        finally:
            self.model.geom_group[:] = saved
        return out

    def object_bounding_sphere(self, object_id: int) -> tuple[FloatArray, float]:
        """Sphere about the object's geom centres enclosing their bounding spheres.

        Kept per object while its geoms stay where they were (a static object's sphere is
        formed once, a moving one's again on each move): the same numbers either way."""
        geoms = self._object_geoms[int(object_id)]
        pos = self.data.geom_xpos[geoms]
        key = pos.tobytes()
        cached = self._spheres.get(int(object_id))
        if cached is not None and cached[0] == key:
            return cached[1].copy(), cached[2]
        centre = np.add.reduce(pos, axis=0) / len(geoms)  # pos.mean(axis=0) without its overhead
        d = pos - centre
        radius = float((np.sqrt(np.add.reduce(d * d, axis=1)) + self.model.geom_rbound[geoms]).max())
        self._spheres[int(object_id)] = (key, centre.copy(), radius)
        return centre, radius
