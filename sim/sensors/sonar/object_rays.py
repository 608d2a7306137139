"""Finer rays over objects that a sonar's base rays sample coarsely (pure numpy).

Shared by every ray-cast sonar (:class:`sim.sensors.fls.FlsSensor`,
:class:`sim.sensors.sss.SssSensor`): the caster's bounding sphere of each object in the
range window is sampled by sub-columns (:meth:`sim.sensors.sonar.ray_fan.RayFan.strip_rays`),
so an object between two base rays still echoes, is labelled and has its nearest range
resolved.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from sim.sensors.raycast import RayCaster
from sim.sensors.sonar.ground_truth import SceneObjectLike
from sim.sensors.sonar.ray_fan import RayFan, RayTable, StripRays, column_neighbours

FloatArray = NDArray[np.float64]
Pairs = tuple[NDArray[np.intp], NDArray[np.intp]]


def add_object_rays(fan: RayFan, base: RayTable, caster: RayCaster, origin_ned: FloatArray, R_ns: FloatArray,
                    objects: Sequence[SceneObjectLike], window_near_m: float, window_far_m: float,
                    max_range_m: float, rays_across: int, span_limit: float | None = None,
                    spheres: dict[int, tuple[FloatArray, float]] | None = None
                    ) -> tuple[RayTable, NDArray[np.int64], Pairs | None]:
    """Append sub-column rays over the objects the base rays sample coarsely.

    Args:
        fan: the sonar's ray fan; base: its cast base rays.
        caster: the scene (objects are refined only if it offers ``object_bounding_sphere``).
        origin_ned: (3,) sonar position (NED, m); R_ns: (3, 3) sonar -> NED rotation.
        objects: scene objects to consider.
        window_near_m, window_far_m: range window (m): only spheres reaching into it count.
        max_range_m: cast range (m).
        rays_across: rays across an object each way (:meth:`RayFan.strip_rays`).
        spheres: object id -> bounding sphere (centre (3,) NED m, radius m) if already known
            (default: asked of the caster).

    Returns:
        The base rays followed by the new rays; per row the object whose sphere it samples
        (-1 for a base ray, -2 for a sub-column ray at a base elevation); and the elevation
        intervals to form echoes from (``None``: the base rays' own).
    """
    n0 = len(base.dist)
    if not objects or not hasattr(caster, "object_bounding_sphere"):
        return base, np.full(n0, -1, dtype=np.int64), None
    near = []
    for o in objects:
        centre, radius = caster.object_bounding_sphere(int(o.id)) if spheres is None else spheres[int(o.id)]
        v = np.asarray(centre, dtype=float) - origin_ned
        if sphere_in_window(v, radius, window_near_m, window_far_m):
            near.append((int(o.id), R_ns.T @ v, float(radius)))
    strips = fan.strip_rays(near, rays_across, span_limit=span_limit)
    if strips.empty:
        return base, np.full(n0, -1, dtype=np.int64), None
    extra = _cast_strips(fan, base, caster, origin_ned, R_ns, strips, max_range_m)
    sampled = base.concat(extra)
    owner = np.concatenate([np.full(n0, -1, dtype=np.int64), np.where(strips.owner < 0, -2, strips.owner)])
    # the replaced columns' base rays leave the echo chains
    chain = np.ones(len(sampled.dist), dtype=bool)
    chain[:n0] = ~np.isin(base.col, strips.columns)
    rows = np.flatnonzero(chain)
    a, b = column_neighbours(sampled.col[rows], sampled.az[rows], sampled.phi[rows])
    return sampled, owner, (rows[a], rows[b])


def sphere_in_window(offset_ned: FloatArray, radius_m: float, window_near_m: float, window_far_m: float) -> bool:
    """Whether a sphere at ``offset_ned`` (3,) from the sonar (m) with ``radius_m`` reaches into
    the range window ``[window_near_m, window_far_m]`` (m)."""
    dist = float(np.sqrt(np.dot(offset_ned, offset_ned)))  # np.linalg.norm's own sum, without its overhead
    return dist - radius_m <= window_far_m and dist + radius_m >= window_near_m


def _cast_strips(fan: RayFan, base: RayTable, caster: RayCaster, origin_ned: FloatArray, R_ns: FloatArray,
                 strips: StripRays, max_range_m: float) -> RayTable:
    """The strip rays, in order; a ray that repeats a base ray (a column left as one sub-column
    keeps its azimuth and the base elevations) is copied from the base table, not cast again."""
    n_el = fan.n_el
    phi_idx = np.minimum(np.searchsorted(fan.elevations_rad, strips.phi), n_el - 1)
    twin = ((strips.owner < 0) & (strips.az == fan.column_azimuths_rad[strips.col])
            & (strips.phi == fan.elevations_rad[phi_idx]) & (strips.weight == 1.0))
    if not twin.any():
        return fan.cast_rays(caster, origin_ned, R_ns, strips.col, strips.az, strips.phi, strips.weight,
                             max_range_m)
    out = base.take(np.where(twin, strips.col * n_el + phi_idx, 0))
    cast = np.flatnonzero(~twin)
    if cast.size:
        new = fan.cast_rays(caster, origin_ned, R_ns, strips.col[cast], strips.az[cast], strips.phi[cast],
                            strips.weight[cast], max_range_m)
        out = out.put(cast, new)
    return out
