"""Echo lines: the echo of each beam (column of rays) versus range (pure numpy + OpenCV).

Consecutive rays of a column that lie on one continuous surface bound a *segment*: its
energy is spread uniformly over the range bins between the two hit ranges, which is what
integrates a beam's elevation aperture into range (elevation ambiguity, a bright leading
edge where a surface faces the sonar, a dark shadow where nothing returns). A segment whose
range has an extremum inside it (a sphere's cap, a cylinder) is split there. Range-only
factors (spreading, absorption, TVG; :mod:`sim.sensors.sonar.propagation`) are applied per bin
afterwards, so they are exact within a segment. Intensities are linear power.

Units: ranges in bin units ``u = (r - window_near) / dr`` where bin k spans ``[k, k + 1)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from sim.sensors.sonar.beam_pattern import two_way_beam_power
from sim.sensors.sonar.fused_passes import kernels
from sim.sensors.sonar.ray_fan import RayTable, Segments, row_dot

FloatArray = NDArray[np.float64]


def ray_strength(rays: RayTable, scattering_exponent: float, elevation_beamwidth_rad: float,
                 elevation_step_rad: float) -> FloatArray:
    """Backscatter strength of each ray's hit, per radian of elevation, in units of one base ray.

    ``reflectivity |cos(incidence)|^scattering_exponent`` (Lambert's law at exponent 2) times
    the two-way elevation beam pattern at the ray's elevation, divided by the base elevation
    step, times the ray's share of its column's azimuth strip. Returns (N,); 0 where nothing
    was hit.
    """
    cos_inc = np.abs(row_dot(rays.dirs, rays.normal))
    strength = rays.refl * cos_inc ** scattering_exponent * two_way_beam_power(
        rays.phi, elevation_beamwidth_rad) / elevation_step_rad
    return strength * rays.weight


@dataclass(frozen=True, slots=True)
class EchoSegments:
    """Range intervals carrying echo energy, one row per interval.

    Attributes:
        line: (M,) column (beam line) index.
        u0, u1: (M,) interval ends in bin units.
        energy: (M,) energy, weighted by ``r0 r1`` (the per-bin gain divides by ``r^2``).
        obj: (M,) object id of the surface that returns it.
    """

    line: NDArray[np.intp]
    u0: FloatArray
    u1: FloatArray
    energy: FloatArray
    obj: NDArray[np.int64]

    def lines(self, n_lines: int, n_bins: int, dtype: type = np.float32) -> NDArray:
        """(n_lines, n_bins) echo energy per range bin (:func:`spread_segments`)."""
        return spread_segments(n_lines, n_bins, self.line, self.u0, self.u1, self.energy, dtype=dtype)


def echo_segments(rays: RayTable, segments: Segments, strength: FloatArray, range_slope: FloatArray,
                  window_near_m: float, range_resolution_m: float) -> EchoSegments:
    """Turn the elevation intervals of the columns into range intervals with their energy.

    What :func:`echo_segments_reference` gives, bit for bit and row for row, in one compiled
    pass (:mod:`sim.sensors.sonar.fused_passes`); see there for the model.
    """
    f64 = np.float64
    line, u0, u1, energy, obj = kernels().echo_segments(
        np.ascontiguousarray(segments.a, dtype=np.intp), np.ascontiguousarray(segments.b, dtype=np.intp),
        np.ascontiguousarray(segments.connected, dtype=np.bool_), np.ascontiguousarray(rays.col, dtype=np.intp),
        np.ascontiguousarray(rays.phi, dtype=f64), np.ascontiguousarray(rays.dist, dtype=f64),
        np.ascontiguousarray(rays.obj, dtype=np.int64), np.ascontiguousarray(strength, dtype=f64),
        np.ascontiguousarray(range_slope, dtype=f64), float(window_near_m), float(range_resolution_m))
    return EchoSegments(line, u0, u1, energy, obj)


def echo_segments_reference(rays: RayTable, segments: Segments, strength: FloatArray, range_slope: FloatArray,
                            window_near_m: float, range_resolution_m: float) -> EchoSegments:
    """Turn the elevation intervals of the columns into range intervals with their energy
    (plain numpy: the specification :func:`echo_segments` is tested against).

    Args:
        rays: the cast rays.
        segments: the intervals (:meth:`sim.sensors.sonar.ray_fan.RayFan.refine_edges`).
        strength: (N,) :func:`ray_strength` of each ray.
        range_slope: (N,) dr/dphi of each hit (m/rad).
        window_near_m, range_resolution_m: the range axis.

    Returns:
        Intervals with positive energy and ranges. A connected interval carries the
        trapezoidal energy of its ends over its elevation span; an unconnected one gives each
        end half its share, at that end's range.
    """
    seg_a, seg_b, conn = segments.a, segments.b, segments.connected
    rr = np.where(np.isfinite(rays.dist), rays.dist, 0.0)
    dphi = rays.phi[seg_b] - rays.phi[seg_a]
    a, b, dc = seg_a[conn], seg_b[conn], dphi[conn]
    e_conn = 0.5 * (strength[a] + strength[b]) * dc
    # A convex/concave surface between two rays (a sphere's cap, a cylinder) has its range
    # extremum inside the segment: locate it with a quadratic r(phi) matched to both ranges
    # and to the slopes dr/dphi = -r (n . d_phi) / (n . d) at the ends, and split there.
    ra, rb = rr[a], rr[b]
    sa, sb = range_slope[a] * dc, range_slope[b] * dc
    dd = ra - rb + sb
    lin = 0.5 * (sa + sb - 2.0 * dd)
    quad = 0.5 * (rb - ra - sa + dd)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_ext = -lin / (2.0 * quad)
    fold = (sa * sb < 0.0) & (t_ext > 0.0) & (t_ext < 1.0)
    t_ext = np.where(fold, t_ext, 1.0)
    r_ext = np.where(fold, ra + lin * t_ext + quad * t_ext ** 2, rb)
    r_ext = _clamp_to_end_tangents(r_ext, fold, ra, rb, sa, sb)
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
    ua = (r0 - window_near_m) / range_resolution_m
    ub = (r1 - window_near_m) / range_resolution_m
    ok = (r0 > 0.0) & (r1 > 0.0) & (energy > 0.0)
    return EchoSegments(rows[ok], ua[ok], ub[ok], energy[ok], obj[ok])


def _clamp_to_end_tangents(r_ext: FloatArray, fold: NDArray[np.bool_], ra: FloatArray, rb: FloatArray,
                           sa: FloatArray, sb: FloatArray) -> FloatArray:
    """Bound each fold's range extremum ``r_ext`` (k,) by the tangents at the interval's ends.

    Over the interval ``t`` in [0, 1] the ends' ranges are ``ra``, ``rb`` and their slopes
    ``sa``, ``sb`` (m per interval, opposite signs at a fold). An arc that turns once lies
    between its chord and its end tangents ``ra + sa t`` and ``rb + sb (t - 1)``: a range
    minimum (``sa < 0``) is no nearer than where the tangents cross, ``r_T``, and no farther
    than the nearer end; a maximum likewise the other way. Near grazing one slope is huge and
    the quadratic through both ends can put its extremum metres off the surface (a diver
    lying along the beam drew a streak of echo metres in front of itself); the clamp keeps
    it on the arc. Where the tangents do not cross inside the interval the ends do not
    support a fold and the extremum stays at the nearer (minimum) or farther (maximum) end.
    Elsewhere (no fold) ``r_ext`` is returned as is.
    """
    is_min = sa < 0.0
    near, far = np.minimum(ra, rb), np.maximum(ra, rb)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_cross = (rb - sb - ra) / (sa - sb)
    r_cross = ra + sa * t_cross
    crosses = (t_cross > 0.0) & (t_cross < 1.0)
    lo = np.where(is_min, np.where(crosses, r_cross, near), far)
    hi = np.where(is_min, near, np.where(crosses, r_cross, far))
    return np.where(fold, np.clip(r_ext, np.minimum(lo, hi), np.maximum(lo, hi)), r_ext)


def spread_segments(n_rows: int, n_bins: int, row: NDArray[np.intp], u_a: FloatArray, u_b: FloatArray,
                    energy: FloatArray, dtype: type = np.float64) -> NDArray:
    """Spread each ``energy`` uniformly over the range interval ``[u_a, u_b]`` of its row.

    Exact bin coverage (a bin gets energy * overlap / length); parts outside
    ``[0, n_bins)`` are dropped. Zero-length intervals go to the bin holding ``u_a``.
    Each interval adds kinks to a float64 array (a segment ``F(x) = density * (relu(x - lo) -
    relu(x - hi))`` puts ``w`` at ``fl + 1`` and ``w (1 - fr)`` at ``fl`` with ``-w (1 - fr)``
    at ``fl + 1`` for each end ``p = fl + fr``; a point ``+E`` at its bin and ``-E`` at the
    next), whose row-wise prefix sums (the differences of consecutive rows of a 2-D integral
    image, :func:`row_cumsum`) are the bin energies, returned as ``dtype``, floored at 0
    (prefix-sum round-off). One compiled pass (:mod:`sim.sensors.sonar.fused_passes`).
    Returns (n_rows, n_bins), non-negative.
    """
    out = np.empty((n_rows, n_bins), dtype=dtype)
    f64 = np.float64
    kernels().spread_segments(int(n_rows), int(n_bins), np.ascontiguousarray(row, dtype=np.intp),
                              np.ascontiguousarray(u_a, dtype=f64), np.ascontiguousarray(u_b, dtype=f64),
                              np.ascontiguousarray(energy, dtype=f64), out)
    return out


def row_cumsum(a: NDArray[np.float64], n_cols: int, dtype: type = np.float64) -> NDArray:
    """Row-wise prefix sums ``cumsum(a, axis=1)[:, :n_cols]`` of a (rows, cols) float64 array.

    Differences of consecutive rows of ``cv2.integral`` (a SIMD 2-D prefix sum, about 3x
    faster than ``np.cumsum`` along rows); the round-off is that of float64 sums over the
    column, ~1e-16 of the column total.
    """
    integral = cv2.integral(np.ascontiguousarray(a, dtype=np.float64), sdepth=cv2.CV_64F)
    return np.subtract(integral[1:, 1:n_cols + 1], integral[:-1, 1:n_cols + 1], dtype=dtype)
