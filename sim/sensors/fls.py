"""Forward-looking sonar (FLS) sensor: ray sampling, image formation and exact ground truth.

Rays: ``azimuth_columns`` x ``elevation_rays`` directions, fixed in the sonar frame
(x boresight, y starboard, z down; azimuth a positive to starboard, elevation phi positive
down: ``[cos a cos phi, sin a cos phi, sin phi]``), rotated into NED with one matmul per
frame. Where two neighbouring rays of a column do not lie on one continuous surface
(a silhouette, a shadow edge) the edge is located by bisection (``edge_refine_iters``
extra casts of one ray per edge), so shadows and object outlines are sharp with few rays.
Intensities come from :mod:`sim.sensors.fls_image`.

Ground truth comes from the same rays: a polar/fan instance mask (object id where an
object's returns land, -1 elsewhere) and per object its box, visible fraction, and the
true polar position of its centroid. The visible fraction of object k is
``(base rays whose first hit is k) / (base rays that hit k when k is cast alone)``; the
second count re-casts, against k's geoms alone, only the base rays inside k's bounding cone
whose first hit is not k (those that hit k hit it alone at the same range)
(:meth:`sim.sensors.raycast.IsolatingRayCaster.cast_isolated`), so it is exact for the
ray grid and cheap (hundreds of rays per object in view; none when k is not hit).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Protocol

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.frames import rot_from_euler
from autonomy.guidance.lawnmower import fls_swath_width_m
from autonomy.messages import FlsFrame
from autonomy.sonar_geometry import FanGeometry
from scenarios.config.fls import FlsConfig
from sim.sensors.fls_image import (
    FanRemap,
    add_speckle_and_noise,
    apply_azimuth_pattern,
    azimuth_kernel,
    spread_segments,
    to_uint8_db,
    transmission_gain,
    tvg_gain,
    two_way_beam_power,
)
from sim.sensors.base import Mount, SceneView, Sensor
from sim.sensors.fls_presets import FlsGeometry, resolve_geometry
from sim.sensors.raycast import BACKGROUND_ID, RayCaster, RayHits
from sim.sensors.registry import register_sensor
from sim.truth import VehicleTruth

FloatArray = NDArray[np.float64]
SURFACE_CHORD_SIN = 0.75  # max |chord . normal| / |chord| for two hits to count as one surface


class SceneObjectLike(Protocol):
    id: int
    name: str
    class_name: str
    is_target: bool
    centroid_ned: FloatArray


@dataclass(frozen=True, slots=True)
class FlsObjectTruth:
    """Ground truth of one scene object in one frame.

    ``bbox_xyxy`` is the fan-image box (px) of the object's returns, widened by half the
    horizontal beam width and one range bin (the beam pattern spreads returns that far);
    ``None`` when no return of it reaches the image. ``visible`` = some of its returns are in
    the image and ``visible_fraction >= min_visible_fraction`` (occluded or out-of-beam
    objects are listed with ``visible=False``). Range/azimuth/elevation are of the centroid
    in the sonar frame at capture.
    """

    id: int
    name: str
    class_name: str
    is_target: bool
    visible: bool
    visible_fraction: float
    n_rays_hit: int
    in_fov: bool
    bbox_xyxy: FloatArray | None
    bbox_polar: tuple[int, int, int, int] | None  # beam0, bin0, beam1, bin1 (inclusive)
    range_m: float
    azimuth_rad: float
    elevation_rad: float
    pos_ned: FloatArray


@dataclass(frozen=True)
class FlsGroundTruth:
    """Per-frame truth: instance masks (object id, -1 = no object), objects, sonar pose.

    ``mask_fan`` (height_px, width_px) is remapped from ``mask_polar`` on first access.
    """

    t_s: float
    mask_polar: NDArray[np.int16]  # (n_beams, n_bins)
    objects: tuple[FlsObjectTruth, ...]
    pos_ned: FloatArray  # (3,) sonar head
    R_ns: FloatArray  # (3, 3) sonar frame -> NED
    fan_remap: FanRemap = field(repr=False, compare=False)

    @cached_property
    def mask_fan(self) -> NDArray[np.int16]:
        return self.fan_remap.labels(self.mask_polar, fill=BACKGROUND_ID)

    def object(self, object_id: int) -> FlsObjectTruth:
        for o in self.objects:
            if o.id == object_id:
                return o
        raise KeyError(f"object {object_id} not in this frame's truth")


@dataclass(frozen=True, slots=True)
class FlsRender:
    """A rendered frame, its ground truth, and the linear intensities behind the image.

    ``mean_intensity``: (n_beams, n_bins) noise-free expected power before TVG;
    ``intensity``: the realisation with speckle and noise (equal to mean + noise floor
    when rendered with ``noise=False``).
    """

    frame: FlsFrame
    truth: FlsGroundTruth
    mean_intensity: NDArray[np.float32]
    intensity: NDArray[np.float32]


def sonar_ray_dirs(azimuth_rad: ArrayLike, elevation_rad: ArrayLike) -> FloatArray:
    """Unit directions in the sonar frame, (..., 3)."""
    a = np.asarray(azimuth_rad, dtype=float)
    p = np.asarray(elevation_rad, dtype=float)
    cp = np.cos(p)
    return np.stack([np.cos(a) * cp, np.sin(a) * cp, np.sin(p)], axis=-1)


def mount_rotation(mount_rpy_rad: ArrayLike) -> FloatArray:
    """Sonar->body rotation from (roll, tilt, yaw); tilt is a pitch *down* of the boresight."""
    roll, tilt, yaw = np.asarray(mount_rpy_rad, dtype=float)
    return rot_from_euler(roll, -tilt, yaw)


def _same_surface(d_a, n_a, o_a, v_a, d_b, n_b, o_b, v_b) -> NDArray[np.bool_]:
    """True where hits a and b lie on one continuous surface: same object, and the chord
    between them runs along both surface normals' tangent planes (no step/edge between)."""
    both = np.isfinite(d_a) & np.isfinite(d_b) & (o_a == o_b)
    chord = np.where(both, d_b, 0.0)[:, None] * v_b
    chord -= np.where(both, d_a, 0.0)[:, None] * v_a
    tol = SURFACE_CHORD_SIN * np.sqrt(_rowdot(chord, chord)) + 1e-9
    return both & (np.abs(_rowdot(chord, n_a)) <= tol) & (np.abs(_rowdot(chord, n_b)) <= tol)


def _rowdot(a: FloatArray, b: FloatArray) -> FloatArray:
    """Row-wise dot products of two (N, 3) arrays."""
    return np.einsum("ij,ij->i", a, b)


@register_sensor(FlsConfig)
class FlsSensor(Sensor[FlsRender]):
    """Forward-looking sonar on the hull.

    Args:
        cfg: the sonar config (preset + overrides).
        mount_pos_body_m: (3,) FRD offset of the sonar head from the body origin.
        mount_rpy_rad: (3,) sonar frame w.r.t. body: roll, tilt (pitch down > 0), yaw;
            default ``(0, cfg.tilt_deg, 0)``.
        rng: generator for speckle and noise (``sim.rng.component_rng(seed, name)``).
        name: the sensor's entry name (default ``fls``).
    """

    def __init__(self, cfg: FlsConfig, mount_pos_body_m: ArrayLike = (0.0, 0.0, 0.0),
                 mount_rpy_rad: ArrayLike | None = None, rng: np.random.Generator | None = None, *,
                 name: str | None = None) -> None:
        self.cfg = cfg
        self.name = name or cfg.kind
        self.geometry: FlsGeometry = resolve_geometry(cfg)
        g = self.geometry
        self.rate_hz = float(cfg.rate_hz)
        self.mount_pos_body_m = np.asarray(mount_pos_body_m, dtype=float).reshape(3)
        rpy = (0.0, np.deg2rad(cfg.tilt_deg), 0.0) if mount_rpy_rad is None else mount_rpy_rad
        self.mount_rpy_rad = np.asarray(rpy, dtype=float).reshape(3)
        self.R_bs = mount_rotation(self.mount_rpy_rad)
        roll, tilt, yaw = self.mount_rpy_rad
        self.mount = Mount(self.mount_pos_body_m, np.array([roll, -tilt, yaw]))  # R_bs as roll/pitch/yaw
        self.reset(rng if rng is not None else np.random.default_rng(0))

        self.n_bins = g.n_bins
        self._col_az = g.column_azimuths_rad()
        self._col_cos, self._col_sin = np.cos(self._col_az), np.sin(self._col_az)
        self._phi = g.elevations_rad()
        self._n_cols, self._n_el = len(self._col_az), len(self._phi)
        self._dphi = float(self._phi[1] - self._phi[0])
        az, el = np.meshgrid(self._col_az, self._phi, indexing="ij")
        self._dirs_s = sonar_ray_dirs(az, el).reshape(-1, 3)  # (n_cols * n_el, 3), column-major
        self._ray_col = np.repeat(np.arange(self._n_cols), self._n_el)
        self._ray_phi = np.tile(self._phi, self._n_cols)
        e = np.arange(self._n_el - 1)
        self._pair_a = (np.arange(self._n_cols)[:, None] * self._n_el + e[None, :]).ravel()
        self._ray_spacing_rad = max(self._dphi, g.fov_rad / self._n_cols)

        bins_m = g.bin_centres_m()
        # r^-2 undoes the r_a r_b weighting of segment energies (see _form_columns)
        self._bin_gain = transmission_gain(bins_m, g.absorption_db_per_m) / np.maximum(bins_m, 1e-3) ** 2
        self._bin_gain32 = self._bin_gain.astype(np.float32)
        self._tvg = tvg_gain(bins_m, cfg.tvg_spreading_db_per_decade,
                             g.absorption_db_per_m if cfg.tvg_absorption else 0.0).astype(np.float32)
        self._kernel = azimuth_kernel(g.fov_rad / self._n_cols, g.beamwidth_az_rad, cfg.side_lobe_extent_beamwidths)
        self._noise_power = 10.0 ** (0.1 * cfg.noise_floor_db)
        beam_az = g.beam_azimuths_rad()
        self._beam_az = beam_az
        col_step = g.fov_rad / self._n_cols
        self._beam_col = np.clip(np.round((beam_az - self._col_az[0]) / col_step), 0, self._n_cols - 1).astype(np.intp)
        self._bbox_beam_pad = int(np.ceil(0.5 * g.beamwidth_az_rad / g.beam_spacing_rad))
        w, h = g.fan_size_px
        self.fan_geometry = FanGeometry.fit(w, h, g.window_near_m, g.window_far_m, g.fov_rad)
        self._remap = FanRemap(self.fan_geometry, beam_az, g.window_near_m, g.range_resolution_m, self.n_bins)

    # -- sensor contract --------------------------------------------------------------------
    @classmethod
    def from_config(cls, name: str, cfg: FlsConfig, mount: Mount | ArrayLike,
                    rng: np.random.Generator) -> "FlsSensor":
        """Head at the mount's position; roll and yaw from the mount, tilt from ``cfg.tilt_deg``."""
        m = mount if isinstance(mount, Mount) else Mount(np.asarray(mount, dtype=float))
        rpy = np.array([m.rpy_rad[0], np.deg2rad(cfg.tilt_deg), m.rpy_rad[2]])
        return cls(cfg, m.pos_body_m, rpy, rng, name=name)

    def reset(self, rng: np.random.Generator) -> None:
        """Take a new speckle and noise stream."""
        self.rng = self._rng = rng

    def ideal(self, truth: VehicleTruth, scene: SceneView) -> FlsRender:
        """The expected frame (no speckle, no receiver noise draws)."""
        return self.measure(truth, scene, noise=False)

    def measure(self, truth: VehicleTruth, scene: SceneView, *, noise: bool = True) -> FlsRender:
        """Render from the true vehicle state (sonar head at the mount point) among the scene's
        objects at capture time."""
        return self.render(truth.t_s, truth.point_ned(self.mount_pos_body_m), truth.R_nb,
                           scene.require_caster("FlsSensor"), scene.objects, noise=noise)

    # -- public ---------------------------------------------------------------------------
    @property
    def n_rays(self) -> int:
        """Base rays per frame (edge refinement adds a few per discontinuity)."""
        return len(self._dirs_s)

    def swath_width_m(self, altitude_m: float) -> float:
        """Across-track width of flat seabed seen at ``altitude_m`` (level vehicle)."""
        g = self.geometry
        return fls_swath_width_m(altitude_m, float(self.mount_rpy_rad[1]), g.fov_rad, g.vertical_beamwidth_rad,
                                 g.window_near_m, g.window_far_m)

    def render(self, t_s: float, pos_ned: ArrayLike, R_nb: ArrayLike, caster: RayCaster,
               objects: Sequence[SceneObjectLike] = (), *, noise: bool = True) -> FlsRender:
        """Render one frame.

        Args:
            t_s: capture time.
            pos_ned: (3,) NED position of the sonar head.
            R_nb: (3, 3) body->NED rotation of the vehicle.
            caster: the scene (MuJoCo or analytic).
            objects: scene objects to report ground truth for.
            noise: draw speckle and receiver noise (False: expected image).
        """
        g = self.geometry
        origin = np.asarray(pos_ned, dtype=float).reshape(3)
        R_ns = np.asarray(R_nb, dtype=float) @ self.R_bs
        dirs = self._dirs_s @ R_ns.T
        base = caster.cast(origin, dirs, g.range_max_m)
        rays = _RayTable.from_hits(base, dirs, self._ray_col, self._ray_phi)
        n0 = len(dirs)

        # neighbour pairs along elevation; refine the discontinuities that matter
        pa, pb = self._pair_a, self._pair_a + 1
        same = rays.same_surface(pa, pb)
        both_miss = ~np.isfinite(rays.dist[pa]) & ~np.isfinite(rays.dist[pb])
        near_enough = np.minimum(rays.dist[pa], rays.dist[pb]) <= g.window_far_m
        refine = ~same & ~both_miss & near_enough
        if self.cfg.edge_refine_iters > 0 and refine.any():
            ra, rb = pa[refine], pb[refine]
            lo, hi = self._bisect(caster, origin, R_ns, rays, ra, rb)
            rays = rays.concat(lo).concat(hi)
            n_ref = len(ra)
            lo_i = n0 + np.arange(n_ref)
            hi_i = n0 + n_ref + np.arange(n_ref)
            keep = ~refine
            seg_a = np.concatenate([pa[keep], ra, lo_i, hi_i])
            seg_b = np.concatenate([pb[keep], lo_i, hi_i, rb])
            new = np.concatenate([ra, lo_i, hi_i]), np.concatenate([lo_i, hi_i, rb])
            conn = np.concatenate([same[keep], rays.same_surface(*new)])
        else:
            seg_a, seg_b, conn = pa, pb, same

        polar_cols, mask_cols, extents = self._form_columns(rays, seg_a, seg_b, conn, R_ns)
        img = np.multiply(polar_cols, self._bin_gain32[None, :], out=polar_cols)
        img = apply_azimuth_pattern(img, self._kernel)
        if self._n_cols != g.n_beams:
            img = cv2.resize(img, (self.n_bins, g.n_beams), interpolation=cv2.INTER_LINEAR)
            mask = mask_cols[self._beam_col]
        else:
            mask = mask_cols
        mean = img
        if noise:
            intensity = add_speckle_and_noise(mean, self.rng, self.cfg.speckle, self._noise_power,
                                              k_shape=self.cfg.k_shape, clutter=mask < 0)
        else:
            intensity = mean + np.float32(self._noise_power)
        polar_u8 = to_uint8_db(intensity, self._tvg, self.cfg.gain_db, self.cfg.dynamic_range_db)
        fan_u8 = self._remap.image(polar_u8)

        in_win = (base.dist_m >= g.window_near_m) & (base.dist_m <= g.window_far_m) & (base.object_id >= 0)
        hits_per_obj = np.bincount(base.object_id[in_win], minlength=1 + max((int(o.id) for o in objects), default=0))
        objs = tuple(self._object_truth(o, origin, R_ns, dirs, base.object_id, int(hits_per_obj[int(o.id)]),
                                        extents.get(int(o.id)), caster) for o in objects)
        frame = FlsFrame(t_s=float(t_s), polar=polar_u8, fan=fan_u8, geometry=self.fan_geometry,
                         mount_pos_body_m=self.mount_pos_body_m.copy(), mount_rpy_rad=self.mount_rpy_rad.copy())
        truth = FlsGroundTruth(t_s=float(t_s), mask_polar=mask, objects=objs, pos_ned=origin.copy(), R_ns=R_ns,
                               fan_remap=self._remap)
        return FlsRender(frame=frame, truth=truth, mean_intensity=mean, intensity=intensity)

    # -- internals --------------------------------------------------------------------------
    def _bisect(self, caster: RayCaster, origin: FloatArray, R_ns: FloatArray, rays: "_RayTable",
                ia: NDArray[np.intp], ib: NDArray[np.intp]) -> tuple["_RayTable", "_RayTable"]:
        """Shrink each (ia, ib) elevation interval onto the edge between ia's surface and the next.

        An interval stops once both its ends lie beyond the range window (as base pairs beyond
        it are not refined): what is left of it cannot put energy into the image."""
        lo, hi = rays.take(ia), rays.take(ib)
        far = self.geometry.window_far_m
        for _ in range(self.cfg.edge_refine_iters):
            act = np.flatnonzero(np.minimum(lo.dist, hi.dist) <= far)
            if act.size == 0:
                break
            lo_a, hi_a = lo.take(act), hi.take(act)
            phi = 0.5 * (lo_a.phi + hi_a.phi)
            v = sonar_ray_dirs(self._col_az[lo_a.col], phi) @ R_ns.T
            mid = _RayTable.from_hits(caster.cast(origin, v, self.geometry.range_max_m), v, lo_a.col, phi)
            with_lo = _same_surface(lo_a.dist, lo_a.normal, lo_a.obj, lo_a.dirs, mid.dist, mid.normal, mid.obj,
                                    mid.dirs)
            with_lo |= ~np.isfinite(lo_a.dist) & ~np.isfinite(mid.dist)
            if act.size == len(lo.dist):
                lo, hi = lo_a.where(with_lo, mid), mid.where(with_lo, hi_a)
            else:
                lo, hi = lo.put(act, lo_a.where(with_lo, mid)), hi.put(act, mid.where(with_lo, hi_a))
        return lo, hi

    def _range_slope(self, rays: "_RayTable", R_ns: FloatArray) -> FloatArray:
        """dr/dphi (m/rad) of each hit along its column, from the surface normal."""
        n_s = rays.normal @ R_ns  # normals in the sonar frame
        sp = np.sin(rays.phi)
        # d(dir)/dphi = [-cos a sin phi, -sin a sin phi, cos phi] in the sonar frame
        n_dphi = n_s[:, 2] * np.cos(rays.phi) - (n_s[:, 0] * self._col_cos[rays.col]
                                                 + n_s[:, 1] * self._col_sin[rays.col]) * sp
        n_d = _rowdot(rays.normal, rays.dirs)
        with np.errstate(divide="ignore", invalid="ignore"):
            slope = -np.where(np.isfinite(rays.dist), rays.dist, 0.0) * n_dphi / n_d
        return np.where(np.isfinite(slope), slope, 0.0)

    def _form_columns(self, rays: "_RayTable", seg_a: NDArray[np.intp], seg_b: NDArray[np.intp],
                      conn: NDArray[np.bool_], R_ns: FloatArray
                      ) -> tuple[NDArray[np.float32], NDArray[np.int16], dict]:
        """Bin segment energies into (n_cols, n_bins) float32, label object returns, and give
        each labelled object's (col0, col1, bin0, bin1) extent. ``conn``: per segment, whether
        its two rays lie on one surface (:meth:`_RayTable.same_surface`)."""
        g = self.geometry
        cos_inc = np.abs(_rowdot(rays.dirs, rays.normal))
        strength = rays.refl * cos_inc ** self.cfg.scattering_exponent * two_way_beam_power(
            rays.phi, g.vertical_beamwidth_rad) / self._dphi  # energy in units of one base ray
        rr = np.where(np.isfinite(rays.dist), rays.dist, 0.0)
        dphi = rays.phi[seg_b] - rays.phi[seg_a]
        a, b, dc = seg_a[conn], seg_b[conn], dphi[conn]
        e_conn = 0.5 * (strength[a] + strength[b]) * dc
        # A convex/concave surface between two rays (a sphere's cap, a cylinder) has its range
        # extremum inside the segment: locate it with a quadratic r(phi) matched to both ranges
        # and to the slopes dr/dphi = -r (n . d_phi) / (n . d) at the ends, and split there.
        slope = self._range_slope(rays, R_ns)
        ra, rb = rr[a], rr[b]
        sa, sb = slope[a] * dc, slope[b] * dc
        dd = ra - rb + sb
        lin = 0.5 * (sa + sb - 2.0 * dd)
        quad = 0.5 * (rb - ra - sa + dd)
        with np.errstate(divide="ignore", invalid="ignore"):
            t_ext = -lin / (2.0 * quad)
        fold = (sa * sb < 0.0) & (t_ext > 0.0) & (t_ext < 1.0)
        t_ext = np.where(fold, t_ext, 1.0)
        r_ext = np.where(fold, ra + lin * t_ext + quad * t_ext ** 2, rb)
        f = np.flatnonzero(fold)
        # first part a -> extremum (the whole segment where there is no fold), then extremum -> b
        seg_r0 = np.concatenate([ra, r_ext[f]])
        seg_r1 = np.concatenate([r_ext, rb[f]])
        seg_e = np.concatenate([e_conn * t_ext, e_conn[f] * (1.0 - t_ext[f])])
        seg_row = np.concatenate([rays.col[a], rays.col[a[f]]])
        seg_obj = np.concatenate([rays.obj[a], rays.obj[a[f]]])
        # unconnected ends: each ray keeps half its share of the gap, at its own range
        d = ~conn
        ends = np.concatenate([seg_a[d], seg_b[d]])
        end_e = 0.5 * strength[ends] * np.concatenate([dphi[d], dphi[d]])
        rows = np.concatenate([seg_row, rays.col[ends]])
        r0 = np.concatenate([seg_r0, rr[ends]])
        r1 = np.concatenate([seg_r1, rr[ends]])
        obj = np.concatenate([seg_obj, rays.obj[ends]])
        # within a segment the density follows r^-2 (what a flat seabed gives, dphi/dr ~ h / r^2):
        # spread E * r0 * r1 uniformly and let the per-bin gain apply r^-2
        energy = np.concatenate([seg_e, end_e]) * r0 * r1
        ua = (r0 - g.window_near_m) / g.range_resolution_m
        ub = (r1 - g.window_near_m) / g.range_resolution_m
        ok = (r0 > 0.0) & (r1 > 0.0) & (energy > 0.0)
        rows, ua, ub, energy, obj = rows[ok], ua[ok], ub[ok], energy[ok], obj[ok]
        polar = spread_segments(self._n_cols, self.n_bins, rows, ua, ub, energy, dtype=np.float32)

        mask = np.full((self._n_cols, self.n_bins), BACKGROUND_ID, dtype=np.int16)
        extents: dict[int, tuple[int, int, int, int]] = {}
        ids = np.unique(obj[obj >= 0])
        windows = []
        for k in ids:
            sel = obj == k
            r, ua_k, ub_k = rows[sel], ua[sel], ub[sel]
            k0 = int(np.clip(np.floor(min(ua_k.min(), ub_k.min())), 0, self.n_bins - 1))
            k1 = int(np.clip(np.floor(max(ua_k.max(), ub_k.max())), k0, self.n_bins - 1))
            windows.append((k, sel, int(r.min()), int(r.max()), k0, k1))
        if windows:
            # strongest object per bin, over the union of the objects' windows only
            u_c0, u_k0 = min(w[2] for w in windows), min(w[4] for w in windows)
            u_c1, u_k1 = max(w[3] for w in windows), max(w[5] for w in windows)
            best_u = np.zeros((u_c1 - u_c0 + 1, u_k1 - u_k0 + 1))
            for k, sel, c0, c1, k0, k1 in windows:
                r, ua_k, ub_k = rows[sel], ua[sel], ub[sel]
                e_k = spread_segments(c1 - c0 + 1, k1 - k0 + 1, r - c0, ua_k - k0, ub_k - k0, energy[sel])
                win = best_u[c0 - u_c0:c1 - u_c0 + 1, k0 - u_k0:k1 - u_k0 + 1]
                take = e_k > np.maximum(win, 1e-6 * e_k.max())  # ignore cumsum round-off
                if not take.any():
                    continue
                win[take] = e_k[take]
                mask[c0:c1 + 1, k0:k1 + 1][take] = k
                rows_k = np.flatnonzero(take.any(axis=1))
                bins_k = np.flatnonzero(take.any(axis=0))
                extents[int(k)] = (c0 + int(rows_k[0]), c0 + int(rows_k[-1]), k0 + int(bins_k[0]),
                                   k0 + int(bins_k[-1]))
        return polar, mask, extents

    def _object_truth(self, obj: SceneObjectLike, origin: FloatArray, R_ns: FloatArray, dirs: FloatArray,
                      first_obj: NDArray[np.int64], n_hit: int, extent: tuple[int, int, int, int] | None,
                      caster: RayCaster) -> FlsObjectTruth:
        """Truth record of ``obj``; ``first_obj`` (n_rays,) first-hit object of each base ray and
        ``n_hit`` how many of them hit ``obj`` inside the range window."""
        g = self.geometry
        k = int(obj.id)
        pos = np.asarray(obj.centroid_ned, dtype=float)
        p_s = R_ns.T @ (pos - origin)
        rng_m = float(np.linalg.norm(p_s))
        az = float(np.arctan2(p_s[1], p_s[0]))
        el = float(np.arctan2(p_s[2], np.hypot(p_s[0], p_s[1])))
        in_fov = bool(abs(az) <= 0.5 * g.fov_rad and abs(el) <= 0.5 * g.vertical_beamwidth_rad
                      and g.window_near_m <= rng_m <= g.window_far_m)
        frac = float("nan")
        isolating = hasattr(caster, "cast_isolated")
        if isolating and n_hit == 0:
            frac = 0.0  # no first hit in the window: 0 whatever the isolated count
        elif isolating:
            centre, radius = caster.object_bounding_sphere(k)
            v = np.asarray(centre, dtype=float) - origin
            dist_c = float(np.linalg.norm(v))
            n_alone = 0
            if dist_c - radius <= g.window_far_m:
                if dist_c <= radius:
                    cand = np.ones(len(dirs), dtype=bool)
                else:
                    half = np.arcsin(min(1.0, radius / dist_c)) + self._ray_spacing_rad
                    cand = dirs @ (v / dist_c) >= np.cos(min(half, np.pi))
                # a ray whose first hit is k hits k alone at the same range: only the others are cast
                cand &= first_obj != k
                n_alone = n_hit
                if cand.any():
                    d_alone = caster.cast_isolated(origin, dirs[cand], g.range_max_m, k)
                    n_alone += int(np.count_nonzero((d_alone >= g.window_near_m) & (d_alone <= g.window_far_m)))
            frac = n_hit / n_alone if n_alone > 0 else 0.0
            frac = min(frac, 1.0)
        bbox = bbox_polar = None
        if extent is not None:
            c0, c1, k0, k1 = extent
            pb, nb = self._bbox_beam_pad, self.n_bins
            beam0 = int(np.searchsorted(self._beam_col, c0, side="left"))
            beam1 = int(np.searchsorted(self._beam_col, c1, side="right")) - 1
            b0, b1 = max(beam0 - pb, 0), min(beam1 + pb, g.n_beams - 1)
            k0, k1 = max(k0 - 1, 0), min(k1 + 1, nb - 1)
            bbox_polar = (b0, k0, b1, k1)
            bbox = self._fan_box(b0, k0, b1, k1)
        visible = n_hit > 0 and bbox is not None and (
            np.isnan(frac) or frac >= self.cfg.min_visible_fraction)
        return FlsObjectTruth(
            id=k, name=str(obj.name), class_name=str(obj.class_name), is_target=bool(obj.is_target),
            visible=bool(visible), visible_fraction=frac, n_rays_hit=n_hit, in_fov=in_fov, bbox_xyxy=bbox,
            bbox_polar=bbox_polar, range_m=rng_m, azimuth_rad=az, elevation_rad=el, pos_ned=pos.copy())

    def _fan_box(self, b0: int, k0: int, b1: int, k1: int) -> FloatArray:
        """Fan-image box (px) of the annular sector covering beams b0..b1, bins k0..k1."""
        g = self.geometry
        half = 0.5 * g.beam_spacing_rad
        a0, a1 = self._beam_az[b0] - half, self._beam_az[b1] + half
        r0 = g.window_near_m + k0 * g.range_resolution_m
        r1 = g.window_near_m + (k1 + 1) * g.range_resolution_m
        a = np.linspace(a0, a1, 9)
        if a0 < 0.0 < a1:
            a = np.append(a, 0.0)
        r = np.array([r0, r1])
        x, y = self.fan_geometry.polar_to_pixel(r[:, None], a[None, :])
        w, h = self.fan_geometry.width_px, self.fan_geometry.height_px
        return np.array([np.clip(x.min(), 0, w - 1), np.clip(y.min(), 0, h - 1),
                         np.clip(x.max(), 0, w - 1), np.clip(y.max(), 0, h - 1)])


@dataclass(frozen=True, slots=True)
class _RayTable:
    """Flat table of cast rays: column, elevation, direction (NED) and hit."""

    col: NDArray[np.intp]
    phi: FloatArray
    dirs: FloatArray
    dist: FloatArray
    normal: FloatArray
    refl: FloatArray
    obj: NDArray[np.int64]

    @classmethod
    def from_hits(cls, hits: RayHits, dirs: FloatArray, col: NDArray[np.intp], phi: FloatArray) -> "_RayTable":
        return cls(col, phi, dirs, hits.dist_m, hits.normal_ned, hits.reflectivity, hits.object_id)

    def take(self, idx: NDArray[np.intp]) -> "_RayTable":
        return _RayTable(*(getattr(self, f)[idx] for f in self.__slots__))

    def where(self, cond: NDArray[np.bool_], other: "_RayTable") -> "_RayTable":
        """Row-wise ``other`` where cond, else self."""
        out = []
        for f in self.__slots__:
            a, b = getattr(self, f), getattr(other, f)
            out.append(np.where(cond[:, None] if a.ndim == 2 else cond, b, a))
        return _RayTable(*out)

    def put(self, idx: NDArray[np.intp], rows: "_RayTable") -> "_RayTable":
        """Copy with rows ``idx`` replaced by ``rows``."""
        out = []
        for f in self.__slots__:
            a = getattr(self, f).copy()
            a[idx] = getattr(rows, f)
            out.append(a)
        return _RayTable(*out)

    def concat(self, other: "_RayTable") -> "_RayTable":
        return _RayTable(*(np.concatenate([getattr(self, f), getattr(other, f)]) for f in self.__slots__))

    def same_surface(self, ia: NDArray[np.intp], ib: NDArray[np.intp]) -> NDArray[np.bool_]:
        return _same_surface(self.dist[ia], self.normal[ia], self.obj[ia], self.dirs[ia],
                             self.dist[ib], self.normal[ib], self.obj[ib], self.dirs[ib])
