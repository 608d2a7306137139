"""Closed-form ray caster: a flat horizontal seabed plus spheres and oriented boxes.

Implements :class:`sim.sensors.raycast.IsolatingRayCaster` in pure numpy so sensor tests
can check rendered images against geometry without MuJoCo.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from sim.sensors.raycast import BACKGROUND_ID, NO_HIT_ID, RayHits

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class AnalyticSphere:
    center_ned: FloatArray
    radius_m: float
    object_id: int
    reflectivity: float = 0.9


@dataclass(frozen=True)
class AnalyticBox:
    """Box of half extents ``half_size_m`` (box frame) centred at ``center_ned``; ``R_nb``
    maps box axes to NED."""

    center_ned: FloatArray
    half_size_m: FloatArray
    object_id: int
    reflectivity: float = 0.9
    R_nb: FloatArray = field(default_factory=lambda: np.eye(3))


def _sphere_t(o: FloatArray, d: FloatArray, s: AnalyticSphere) -> tuple[FloatArray, FloatArray]:
    oc = o - np.asarray(s.center_ned, dtype=float)
    b = d @ oc
    disc = b * b - (oc @ oc - s.radius_m ** 2)
    with np.errstate(invalid="ignore"):
        t = -b - np.sqrt(disc)
    t = np.where((disc > 0.0) & (t > 0.0), t, np.inf)
    p = o + np.where(np.isfinite(t), t, 0.0)[:, None] * d
    return t, (p - s.center_ned) / s.radius_m


def _box_t(o: FloatArray, d: FloatArray, b: AnalyticBox) -> tuple[FloatArray, FloatArray]:
    R = np.asarray(b.R_nb, dtype=float)
    h = np.asarray(b.half_size_m, dtype=float)
    ol = R.T @ (o - np.asarray(b.center_ned, dtype=float))
    dl = d @ R
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (-h - ol) / dl
        t2 = (h - ol) / dl
    near = np.nan_to_num(np.minimum(t1, t2), nan=-np.inf)
    far = np.nan_to_num(np.maximum(t1, t2), nan=np.inf)
    t_in, t_out = near.max(axis=1), far.min(axis=1)
    t = np.where((t_out >= t_in) & (t_in > 0.0), t_in, np.inf)
    axis = near.argmax(axis=1)
    n_local = np.zeros_like(d)
    n_local[np.arange(len(d)), axis] = -np.sign(dl[np.arange(len(d)), axis])
    return t, n_local @ R.T


class AnalyticCaster:
    """Flat seabed at ``seabed_depth_m`` (``None``: no seabed) plus spheres and boxes.

    The seabed reports :data:`BACKGROUND_ID`; spheres and boxes their ``object_id``.
    """

    def __init__(self, seabed_depth_m: float | None = None, seabed_reflectivity: float = 0.3,
                 spheres: tuple[AnalyticSphere, ...] = (), boxes: tuple[AnalyticBox, ...] = ()) -> None:
        self.seabed_depth_m = seabed_depth_m
        self.seabed_reflectivity = float(seabed_reflectivity)
        self.shapes: tuple[AnalyticSphere | AnalyticBox, ...] = tuple(spheres) + tuple(boxes)

    def _shape_t(self, o: FloatArray, d: FloatArray, s: AnalyticSphere | AnalyticBox):
        return _sphere_t(o, d, s) if isinstance(s, AnalyticSphere) else _box_t(o, d, s)

    def cast(self, origin_ned: FloatArray, dirs_ned: FloatArray, max_range_m: float) -> RayHits:
        o = np.asarray(origin_ned, dtype=float)
        d = np.asarray(dirs_ned, dtype=float)
        n = len(d)
        dist = np.full(n, np.inf)
        normal = np.zeros((n, 3))
        refl = np.zeros(n)
        obj = np.full(n, NO_HIT_ID, dtype=np.int64)
        if self.seabed_depth_m is not None and o[2] < self.seabed_depth_m:
            with np.errstate(divide="ignore"):
                t = np.where(d[:, 2] > 0.0, (self.seabed_depth_m - o[2]) / d[:, 2], np.inf)
            dist = t
            normal[np.isfinite(t)] = (0.0, 0.0, -1.0)
            refl[:] = self.seabed_reflectivity
            obj[:] = BACKGROUND_ID
        for s in self.shapes:
            t, nrm = self._shape_t(o, d, s)
            closer = t < dist
            dist = np.where(closer, t, dist)
            normal[closer] = nrm[closer]
            refl[closer] = s.reflectivity
            obj[closer] = s.object_id
        miss = ~(dist <= max_range_m)
        dist[miss] = np.inf
        normal[miss] = 0.0
        refl[miss] = 0.0
        obj[miss] = NO_HIT_ID
        return RayHits(dist_m=dist, normal_ned=normal, reflectivity=refl, object_id=obj)

    def cast_isolated(self, origin_ned: FloatArray, dirs_ned: FloatArray, max_range_m: float,
                      object_id: int) -> FloatArray:
        o = np.asarray(origin_ned, dtype=float)
        d = np.asarray(dirs_ned, dtype=float)
        dist = np.full(len(d), np.inf)
        for s in self.shapes:
            if s.object_id == object_id:
                dist = np.minimum(dist, self._shape_t(o, d, s)[0])
        dist[dist > max_range_m] = np.inf
        return dist

    def object_bounding_sphere(self, object_id: int) -> tuple[FloatArray, float]:
        parts = [s for s in self.shapes if s.object_id == object_id]
        if not parts:
            raise KeyError(f"no shape with object_id {object_id}")
        centres = np.array([s.center_ned for s in parts], dtype=float)
        radii = np.array([s.radius_m if isinstance(s, AnalyticSphere) else float(np.linalg.norm(s.half_size_m))
                          for s in parts])
        c = centres.mean(axis=0)
        return c, float(np.max(np.linalg.norm(centres - c, axis=1) + radii))
