"""Ray sampling of a sonar's beams: columns of rays at fixed azimuths across the elevation aperture.

A *column* is one azimuth; its rays sample the elevation aperture from up (negative) to
down (positive) in the sonar frame of :mod:`autonomy.sonar_frame`. Any beam layout is a set
of columns: a forward-looking sonar has hundreds across its horizontal field of view, a
single-beam scanning sonar one (rotated by its mount yaw each ping), a side-scan sonar one
per side (mount yaw +-90 deg, tilted down by the depression angle).

Consecutive rays of a column that lie on one continuous surface bound a *segment* whose echo
is spread between the two hit ranges (:mod:`sim.sensors.sonar.echo_lines`). Where two
neighbours do not (a silhouette, a shadow edge) the edge is located by bisection
(:meth:`RayFan.refine_edges`), so shadows and outlines are sharp with few rays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.sonar_frame import ray_directions_sonar
from sim.sensors.raycast import RayCaster, RayHits
from sim.sensors.sonar.fused_passes import kernels

FloatArray = NDArray[np.float64]
SURFACE_CHORD_SIN = 0.75  # max |chord . normal| / |chord| for two hits to count as one surface


def row_dot(a: FloatArray, b: FloatArray) -> FloatArray:
    """Row-wise dot products of two (N, 3) arrays -> (N,)."""
    return np.einsum("ij,ij->i", a, b)


def same_surface(d_a: FloatArray, n_a: FloatArray, o_a: NDArray[np.int64], v_a: FloatArray, d_b: FloatArray,
                 n_b: FloatArray, o_b: NDArray[np.int64], v_b: FloatArray) -> NDArray[np.bool_]:
    """True where hits a and b lie on one continuous surface.

    Both rays hit the same object and the chord between the hit points runs within
    ``asin(SURFACE_CHORD_SIN)`` of both surface tangent planes (no step or edge between).

    Args:
        d_a, d_b: (N,) hit distances (m, ``inf`` for a miss).
        n_a, n_b: (N, 3) unit surface normals at the hits (NED).
        o_a, o_b: (N,) object ids hit.
        v_a, v_b: (N, 3) unit ray directions (NED).

    Returns:
        (N,) bool.
    """
    every = np.arange(len(d_a))
    return same_surface_rows(d_a, n_a, o_a, v_a, every, d_b, n_b, o_b, v_b, every)


def same_surface_rows(d_a: FloatArray, n_a: FloatArray, o_a: NDArray[np.int64], v_a: FloatArray,
                      ia: NDArray[np.intp], d_b: FloatArray, n_b: FloatArray, o_b: NDArray[np.int64],
                      v_b: FloatArray, ib: NDArray[np.intp]) -> NDArray[np.bool_]:
    """:func:`same_surface` of rows ``ia`` of the a arrays against rows ``ib`` of the b arrays
    (M,), without gathering them: one compiled pass
    (:mod:`sim.sensors.sonar.fused_passes`; the chord is ``d_b v_b - d_a v_a`` where both rays
    hit, the tolerance ``SURFACE_CHORD_SIN |chord| + 1e-9``)."""
    return kernels().same_surface(d_a, n_a, o_a, v_a, np.asarray(ia, dtype=np.intp), d_b, n_b, o_b, v_b,
                                  np.asarray(ib, dtype=np.intp), SURFACE_CHORD_SIN)


@dataclass(frozen=True, slots=True)
class RayTable:
    """Flat table of N cast rays.

    Attributes:
        col: (N,) column (echo line) of each ray.
        az: (N,) azimuth of the ray in the sonar frame (rad): its column's, or a sub-column's
            inside the column's azimuth strip.
        phi: (N,) elevation in the sonar frame (rad, down > 0).
        weight: (N,) share of its column's azimuth strip the ray's chain stands for (1 for a
            base ray, ``1 / n`` for one of n sub-columns).
        dirs: (N, 3) unit direction (NED).
        dist: (N,) distance to the first hit (m, ``inf`` where nothing was hit).
        normal: (N, 3) surface normal at the hit (NED).
        refl: (N,) reflectivity of the surface hit.
        obj: (N,) object id hit (see :class:`sim.sensors.raycast.RayHits`).
    """

    col: NDArray[np.intp]
    az: FloatArray
    phi: FloatArray
    weight: FloatArray
    dirs: FloatArray
    dist: FloatArray
    normal: FloatArray
    refl: FloatArray
    obj: NDArray[np.int64]

    @classmethod
    def from_hits(cls, hits: RayHits, dirs: FloatArray, col: NDArray[np.intp], az: FloatArray, phi: FloatArray,
                  weight: FloatArray) -> "RayTable":
        return cls(col, az, phi, weight, dirs, hits.dist_m, hits.normal_ned, hits.reflectivity, hits.object_id)

    def take(self, idx: NDArray[np.intp]) -> "RayTable":
        return RayTable(*(getattr(self, f)[idx] for f in self.__slots__))

    def where(self, cond: NDArray[np.bool_], other: "RayTable") -> "RayTable":
        """Row-wise ``other`` where cond, else self."""
        out = []
        for f in self.__slots__:
            a, b = getattr(self, f), getattr(other, f)
            out.append(np.where(cond[:, None] if a.ndim == 2 else cond, b, a))
        return RayTable(*out)

    def put(self, idx: NDArray[np.intp], rows: "RayTable") -> "RayTable":
        """Copy with rows ``idx`` replaced by ``rows``."""
        out = []
        for f in self.__slots__:
            a = getattr(self, f).copy()
            a[idx] = getattr(rows, f)
            out.append(a)
        return RayTable(*out)

    def concat(self, other: "RayTable") -> "RayTable":
        return RayTable.stack([self, other])

    @staticmethod
    def stack(tables: "list[RayTable]") -> "RayTable":
        """The rows of ``tables``, one after the other."""
        return RayTable(*(np.concatenate([getattr(t, f) for t in tables]) for f in RayTable.__slots__))

    def same_surface(self, ia: NDArray[np.intp], ib: NDArray[np.intp]) -> NDArray[np.bool_]:
        """:func:`same_surface` of rows ``ia`` and ``ib``."""
        return same_surface_rows(self.dist, self.normal, self.obj, self.dirs, ia,
                                 self.dist, self.normal, self.obj, self.dirs, ib)


@dataclass(frozen=True, slots=True)
class Segments:
    """Pairs of rays that bound the elevation intervals of the columns.

    Attributes:
        a, b: (M,) row indices (into a :class:`RayTable`) of each interval's upper and lower ray.
        connected: (M,) whether both ends lie on one continuous surface.
    """

    a: NDArray[np.intp]
    b: NDArray[np.intp]
    connected: NDArray[np.bool_]


def column_neighbours(col: NDArray[np.intp], az: FloatArray, phi: FloatArray
                      ) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Pairs of rows that are elevation neighbours on one chain (same column and azimuth).

    Args:
        col: (N,) column of each ray; az: (N,) its azimuth; phi: (N,) its elevation.

    Returns:
        ``(a, b)``: row indices with ``phi[a] <= phi[b]``, consecutive on their chain.
    """
    order = np.lexsort((phi, az, col))
    a, b = order[:-1], order[1:]
    same = (col[a] == col[b]) & (az[a] == az[b])
    return a[same], b[same]


@dataclass(frozen=True, slots=True)
class StripRays:
    """Rays that replace some columns by finer sub-columns (:meth:`RayFan.strip_rays`).

    Attributes:
        columns: (K,) the columns replaced.
        col, az, phi, weight: (M,) the new rays (see :class:`RayTable`).
        owner: (M,) object id whose sphere a ray samples, -1 for a ray at a base elevation.
    """

    columns: NDArray[np.intp]
    col: NDArray[np.intp]
    az: FloatArray
    phi: FloatArray
    weight: FloatArray
    owner: NDArray[np.int64]

    @property
    def empty(self) -> bool:
        return len(self.col) == 0


class RayFan:
    """A sonar's base rays: ``len(column_azimuths_rad)`` columns x ``len(elevations_rad)`` rays.

    Args:
        column_azimuths_rad: (n_cols,) column azimuths in the sonar frame (rad, starboard > 0).
        elevations_rad: (n_el,) increasing, evenly spaced ray elevations (rad, down > 0),
            at least two.

    Rays are stored column-major: ray ``i`` is column ``i // n_el``, elevation ``i % n_el``.

    Raises:
        ValueError: fewer than two elevations or none increasing.
    """

    def __init__(self, column_azimuths_rad: ArrayLike, elevations_rad: ArrayLike) -> None:
        self.column_azimuths_rad = np.asarray(column_azimuths_rad, dtype=float).reshape(-1)
        self.elevations_rad = np.asarray(elevations_rad, dtype=float).reshape(-1)
        if len(self.elevations_rad) < 2 or not np.all(np.diff(self.elevations_rad) > 0.0):
            raise ValueError("elevations_rad must hold at least two increasing values")
        self.n_cols, self.n_el = len(self.column_azimuths_rad), len(self.elevations_rad)
        self.elevation_step_rad = float(self.elevations_rad[1] - self.elevations_rad[0])
        az, el = np.meshgrid(self.column_azimuths_rad, self.elevations_rad, indexing="ij")
        self.dirs_sonar = ray_directions_sonar(az, el).reshape(-1, 3)  # (n_cols * n_el, 3)
        self.ray_col = np.repeat(np.arange(self.n_cols), self.n_el)
        self.ray_az = np.repeat(self.column_azimuths_rad, self.n_el)
        self.ray_phi = np.tile(self.elevations_rad, self.n_cols)
        self._ray_weight = np.ones(self.n_rays)
        self.column_width_rad = (float(self.column_azimuths_rad[1] - self.column_azimuths_rad[0])
                                 if self.n_cols > 1 else 0.0)
        e = np.arange(self.n_el - 1)
        self._pair_a = (np.arange(self.n_cols)[:, None] * self.n_el + e[None, :]).ravel()

    @property
    def base_pairs(self) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        """Rows (upper, lower) of the elevation neighbours among the base rays."""
        return self._pair_a, self._pair_a + 1

    @property
    def n_rays(self) -> int:
        """Base rays per cast."""
        return len(self.dirs_sonar)

    def cast(self, caster: RayCaster, origin_ned: FloatArray, R_ns: FloatArray,
             max_range_m: float) -> tuple[RayTable, RayHits]:
        """Cast the base rays from ``origin_ned`` (3,) with sonar->NED rotation ``R_ns`` (3, 3).

        Returns:
            The ray table (rows in base-ray order) and the caster's raw hits.
        """
        dirs = self.dirs_sonar @ R_ns.T
        hits = caster.cast(origin_ned, dirs, max_range_m)
        return RayTable.from_hits(hits, dirs, self.ray_col, self.ray_az, self.ray_phi, self._ray_weight), hits

    def strip_rays(self, spheres: list[tuple[int, FloatArray, float]], rays_across: int,
                   max_sub_columns: int = 8, span_limit: float | None = None) -> StripRays:
        """Finer rays over spheres that the base rays sample coarsely (small objects between them).

        A sphere (object id, centre (3,) in the sonar frame, radius m) subtending ``2 beta``
        with ``2 beta < rays_across * max(elevation step, column width)`` is sampled at the
        spacing ``s = 2 beta / rays_across``: every column whose azimuth strip (its width
        about its azimuth) overlaps the sphere's azimuth extent is replaced by ``n`` evenly
        spaced sub-columns (``n = ceil(width / s)``, at most ``max_sub_columns``, the largest
        over the spheres it meets) of weight ``1 / n``. Each sub-column carries the base
        elevations plus, where the sub-column's azimuth plane cuts a sphere's cone of directions,
        that chord's elevations inside the base elevation span at spacing ``s``, cell-centred.
        A direction ``d(a, phi)`` lies in the cone when ``d . u >= cos(beta)`` (``u`` the unit
        direction to the centre, ``sin(beta) = radius / distance``); ``d . u = rho cos(phi - psi)``
        with ``rho = |(cos a u_x + sin a u_y, u_z)|`` and ``psi = atan2(u_z, cos a u_x + sin a u_y)``,
        so the chord is ``psi +- acos(cos(beta) / rho)``.

        Returns:
            The replaced columns and the rays of their sub-columns (empty when no sphere needs
            finer rays, or the sonar is inside a sphere).
        """
        el0, el1 = float(self.elevations_rad[0]), float(self.elevations_rad[-1])
        width = self.column_width_rad
        coarse = max(self.elevation_step_rad, width)
        limit = rays_across if span_limit is None else span_limit
        needs: list[tuple[int, FloatArray, float, float]] = []  # (id, u, cos beta, spacing)
        n_sub: dict[int, int] = {}
        for oid, centre, radius in spheres:
            c = np.asarray(centre, dtype=float).reshape(3)
            dist = float(np.sqrt(np.dot(c, c)))  # np.linalg.norm's own sum, without its overhead
            if not dist > radius:
                continue
            u = c / dist
            beta = float(np.arcsin(radius / dist))
            el_c = float(np.arcsin(min(max(float(u[2]), -1.0), 1.0)))
            if 2.0 * beta >= limit * coarse or el_c - beta > el1 or el_c + beta < el0:
                continue
            spacing = 2.0 * beta / rays_across
            cos_el = np.cos(el_c)
            half_az = np.pi if cos_el <= np.sin(beta) else float(np.arcsin(np.sin(beta) / cos_el))
            az_c = float(np.arctan2(u[1], u[0]))
            lo_gap = np.abs(np.angle(np.exp(1j * (self.column_azimuths_rad - az_c))))
            cols = np.flatnonzero(lo_gap <= half_az + 0.5 * width)
            if cols.size == 0:
                continue
            n = int(min(max(np.ceil(width / spacing), 1), max_sub_columns))
            for c_i in cols.tolist():
                n_sub[c_i] = max(n_sub.get(c_i, 1), n)
            needs.append((int(oid), u, float(np.cos(beta)), spacing))
        if not needs:
            z = np.zeros(0)
            return StripRays(np.zeros(0, dtype=np.intp), z.astype(np.intp), z, z, z, z.astype(np.int64))
        columns = np.array(sorted(n_sub), dtype=np.intp)
        counts = np.array([n_sub[c] for c in columns.tolist()])
        sub_col = np.repeat(columns, counts)
        starts = np.repeat(np.cumsum(counts) - counts, counts)
        j = np.arange(len(sub_col)) - starts
        n_of = np.repeat(counts, counts)
        sub_az = self.column_azimuths_rad[sub_col] + ((j + 0.5) / n_of - 0.5) * width
        sub_w = 1.0 / n_of
        # every sub-column carries the base elevations
        col = [np.repeat(sub_col, self.n_el)]
        az = [np.repeat(sub_az, self.n_el)]
        phi = [np.tile(self.elevations_rad, len(sub_col))]
        weight = [np.repeat(sub_w, self.n_el)]
        owner = [np.full(len(sub_col) * self.n_el, -1, dtype=np.int64)]
        ca, sa = np.cos(sub_az), np.sin(sub_az)
        for oid, u, cos_beta, spacing in needs:
            A = ca * u[0] + sa * u[1]
            rho = np.hypot(A, u[2])
            cut = np.flatnonzero(rho > cos_beta)
            psi = np.arctan2(u[2], A[cut])
            delta = np.arccos(cos_beta / rho[cut])
            lo = np.maximum(psi - delta, el0)
            hi = np.minimum(psi + delta, el1)
            ok = hi > lo
            cut, lo, hi = cut[ok], lo[ok], hi[ok]
            n = np.maximum(np.ceil((hi - lo) / spacing), 1).astype(np.intp)
            first = np.repeat(np.cumsum(n) - n, n)
            k = np.arange(int(n.sum())) - first
            nn = np.repeat(n, n)
            col.append(np.repeat(sub_col[cut], n))
            az.append(np.repeat(sub_az[cut], n))
            phi.append(np.repeat(lo, n) + np.repeat(hi - lo, n) * (k + 0.5) / nn)
            weight.append(np.repeat(sub_w[cut], n))
            owner.append(np.full(int(n.sum()), oid, dtype=np.int64))
        return StripRays(columns, np.concatenate(col), np.concatenate(az), np.concatenate(phi),
                         np.concatenate(weight), np.concatenate(owner))

    def cast_rays(self, caster: RayCaster, origin_ned: FloatArray, R_ns: FloatArray, col: NDArray[np.intp],
                  az: FloatArray, phi: FloatArray, weight: FloatArray, max_range_m: float) -> RayTable:
        """Cast rays (M,) of columns ``col`` at azimuths ``az`` and elevations ``phi`` (rad).

        ``R_ns`` is one sonar->NED rotation (3, 3), or one per block of ``n_cols`` columns
        (B, 3, 3): column ``c`` then belongs to the sonar ``c // n_cols`` (several sonars at
        one origin, e.g. the two sides of a side-scan, cast together).
        """
        if R_ns.ndim == 2:
            v = ray_directions_sonar(az, phi) @ R_ns.T
        else:
            block = col // self.n_cols
            v = np.empty((len(col), 3))
            for b, R_b in enumerate(R_ns):
                m = block == b
                v[m] = ray_directions_sonar(az[m], phi[m]) @ R_b.T
        return RayTable.from_hits(caster.cast(origin_ned, v, max_range_m), v, col, az, phi, weight)

    def refine_edges(self, caster: RayCaster, origin_ned: FloatArray, R_ns: FloatArray, rays: RayTable,
                     max_range_m: float, window_far_m: float, iters: int,
                     pairs: tuple[NDArray[np.intp], NDArray[np.intp]] | None = None) -> tuple[RayTable, Segments]:
        """Split elevation intervals at surface edges.

        The intervals are ``pairs`` (rows of ``rays``, upper then lower ray of each; default
        the base rays' neighbours, for a table holding the base rays only). Intervals whose ends
        are not on one surface, not both misses, and not both beyond ``window_far_m`` are
        bisected ``iters`` times (:meth:`bisect`); each becomes three intervals: upper ray ->
        last point on its surface, that point -> first point past the edge, that point ->
        lower ray.

        Returns:
            The ray table with the refinement rays appended, and the intervals.
        """
        pa, pb = self.base_pairs if pairs is None else pairs
        same = rays.same_surface(pa, pb)
        both_miss = ~np.isfinite(rays.dist[pa]) & ~np.isfinite(rays.dist[pb])
        near_enough = np.minimum(rays.dist[pa], rays.dist[pb]) <= window_far_m
        refine = ~same & ~both_miss & near_enough
        if iters <= 0 or not refine.any():
            return rays, Segments(pa, pb, same)
        n0 = len(rays.dist)
        ra, rb = pa[refine], pb[refine]
        lo, hi = self.bisect(caster, origin_ned, R_ns, rays, ra, rb, max_range_m, window_far_m, iters)
        rays = RayTable.stack([rays, lo, hi])
        n_ref = len(ra)
        lo_i = n0 + np.arange(n_ref)
        hi_i = n0 + n_ref + np.arange(n_ref)
        keep = ~refine
        seg_a = np.concatenate([pa[keep], ra, lo_i, hi_i])
        seg_b = np.concatenate([pb[keep], lo_i, hi_i, rb])
        new = np.concatenate([ra, lo_i, hi_i]), np.concatenate([lo_i, hi_i, rb])
        conn = np.concatenate([same[keep], rays.same_surface(*new)])
        return rays, Segments(seg_a, seg_b, conn)

    def bisect(self, caster: RayCaster, origin_ned: FloatArray, R_ns: FloatArray, rays: RayTable,
               ia: NDArray[np.intp], ib: NDArray[np.intp], max_range_m: float, window_far_m: float,
               iters: int) -> tuple[RayTable, RayTable]:
        """Shrink each (ia, ib) elevation interval onto the edge between ia's surface and the next.

        One cast per level for all intervals still open.

        An interval stops once both its ends lie beyond ``window_far_m`` (as base pairs beyond
        it are not refined): what is left of it cannot put energy into the image.

        Returns:
            (lo, hi): the rays just before and just past each edge, one row per interval.
        """
        n = len(ia)
        # The loop carries only what it reads (range, normal, object, direction, elevation of each
        # end) and, per end, the row of the ray it holds in a pool of every ray met (the two end
        # tables, then each level's casts); the full rows are gathered once at the end.
        lo_t, hi_t = rays.take(ia), rays.take(ib)
        lo_d, lo_n, lo_o, lo_v, lo_p = (a.copy() for a in (lo_t.dist, lo_t.normal, lo_t.obj, lo_t.dirs, lo_t.phi))
        hi_d, hi_p = hi_t.dist.copy(), hi_t.phi.copy()
        lo_row, hi_row = np.arange(n), np.arange(n, 2 * n)
        pool, n_pool = [lo_t, hi_t], 2 * n
        for _ in range(iters):
            act = np.flatnonzero(np.minimum(lo_d, hi_d) <= window_far_m)
            if act.size == 0:
                break
            whole = act.size == n
            if whole:  # column, azimuth and weight never change
                col, az, weight, a_p, b_p = lo_t.col, lo_t.az, lo_t.weight, lo_p, hi_p
            else:
                col, az, weight, a_p, b_p = lo_t.col[act], lo_t.az[act], lo_t.weight[act], lo_p[act], hi_p[act]
            mid = self.cast_rays(caster, origin_ned, R_ns, col, az, 0.5 * (a_p + b_p), weight, max_range_m)
            # the mid ray replaces the end whose surface it lies on (the lower end also where
            # both miss): one compiled pass (:func:`same_surface`'s test, then the updates)
            kernels().bisect_level(lo_d, lo_n, lo_o, lo_v, lo_p, lo_row, hi_d, hi_p, hi_row, act, mid.dist,
                                   mid.normal, mid.obj, mid.dirs, mid.phi, n_pool, SURFACE_CHORD_SIN)
            pool.append(mid)
            n_pool += act.size
        if len(pool) == 2:
            return lo_t, hi_t
        every = RayTable.stack(pool)
        return every.take(lo_row), every.take(hi_row)

    def range_slope(self, rays: RayTable, R_ns: FloatArray) -> FloatArray:
        """dr/dphi (m/rad) of each hit along its column, from the surface normal; 0 where no hit.

        For a ray ``d(phi)`` meeting a surface of normal ``n`` at range ``r``,
        ``dr/dphi = -r (n . dd/dphi) / (n . d)``.
        """
        n_s = rays.normal @ R_ns  # normals in the sonar frame
        sp = np.sin(rays.phi)
        # d(dir)/dphi = [-cos a sin phi, -sin a sin phi, cos phi] in the sonar frame
        n_dphi = n_s[:, 2] * np.cos(rays.phi) - (n_s[:, 0] * np.cos(rays.az) + n_s[:, 1] * np.sin(rays.az)) * sp
        n_d = row_dot(rays.normal, rays.dirs)
        with np.errstate(divide="ignore", invalid="ignore"):
            slope = -np.where(np.isfinite(rays.dist), rays.dist, 0.0) * n_dphi / n_d
        return np.where(np.isfinite(slope), slope, 0.0)
