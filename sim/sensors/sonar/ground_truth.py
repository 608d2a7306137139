"""Exact ground truth of a sonar frame from the rays that formed it (pure numpy).

* Per-bin labels: in each (line, range bin) the scene object whose echo energy there is the
  strongest, :data:`sim.sensors.raycast.BACKGROUND_ID` where no object echoes
  (:func:`label_bins`).
* Visible fraction of object k: ``(rays whose first hit is k) / (rays that hit k when k is cast
  alone)``; the second count re-casts, against k's geoms alone, only the rays inside k's
  bounding cone whose first hit is not k (those that hit k hit it alone at the same range)
  (:func:`visible_fraction`), so it is exact for the ray set and cheap.
* Where the object is: slant range, azimuth and elevation of its centroid in the sonar frame
  (:func:`centroid_polar`).

The record (:class:`SonarGroundTruth`) of a frame rendered without the objects' truth keeps the
sonar pose only; reading its objects or labels raises :class:`SonarTruthNotComputedError`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from autonomy.sonar_frame import sonar_to_spherical
from sim.sensors.base import SceneObjectLike
from sim.sensors.raycast import BACKGROUND_ID, RayCaster
from sim.sensors.sonar.display import FanRemap
from sim.sensors.sonar.echo_lines import EchoSegments, spread_segments

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class SonarObjectTruth:
    """Ground truth of one scene object in one frame.

    ``bbox_polar`` = (beam0, bin0, beam1, bin1), inclusive, of the object's returns, widened by
    half the horizontal beam width and one range bin (the beam pattern spreads returns that
    far); ``bbox_xyxy`` the same box in the fan image (px); both ``None`` when no return of it
    reaches the image. ``visible``: some of its returns are in the image and
    ``visible_fraction >= min_visible_fraction`` (occluded or out-of-beam objects are listed
    with ``visible=False``). Range (m), azimuth and elevation (rad) are of the centroid in the
    sonar frame at capture; ``in_fov``: they lie inside the beam and range window.
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
    bbox_polar: tuple[int, int, int, int] | None
    range_m: float
    azimuth_rad: float
    elevation_rad: float
    pos_ned: FloatArray


class SonarTruthNotComputedError(RuntimeError):
    """The frame was rendered without its objects' ground truth and instance mask
    (:meth:`sim.sensors.fls.FlsSensor.render` with ``truth=False``; in a mission: no observer
    declared ``sonar_truth = True``)."""


@dataclass(frozen=True, init=False)
class SonarGroundTruth:
    """Per-frame truth: instance labels (object id, -1 = no object), objects, sonar pose.

    A frame rendered without its objects' truth (``FlsSensor.render(..., truth=False)``) keeps
    the pose (``t_s``, ``pos_ned``, ``R_ns``) but not the objects and labels: reading
    ``objects``, ``mask_polar``, ``mask_fan`` or :meth:`object` then raises
    :class:`SonarTruthNotComputedError` (``objects_computed`` tells which kind of frame it is).

    Attributes:
        t_s: capture time (s).
        mask_polar: (n_beams, n_bins) int16 object id per beam and range bin.
        objects: one record per scene object asked for.
        pos_ned: (3,) sonar head position (NED, m).
        R_ns: (3, 3) sonar frame -> NED rotation.
        fan_remap: the polar -> fan resampling behind ``mask_fan`` (fan-shaped sonars).

    Args:
        mask_polar, objects: None (both) for a frame rendered without its objects' truth.

    Raises:
        ValueError: one of ``mask_polar`` and ``objects`` is None and the other is not.
    """

    t_s: float
    pos_ned: FloatArray
    R_ns: FloatArray
    fan_remap: FanRemap | None = field(default=None, repr=False, compare=False)
    _mask_polar: NDArray[np.int16] | None = field(default=None, repr=False, compare=False)
    _objects: tuple[SonarObjectTruth, ...] | None = field(default=None, compare=False)

    def __init__(self, t_s: float, mask_polar: NDArray[np.int16] | None,
                 objects: tuple[SonarObjectTruth, ...] | None, pos_ned: FloatArray, R_ns: FloatArray,
                 fan_remap: FanRemap | None = None) -> None:
        if (mask_polar is None) != (objects is None):
            raise ValueError("SonarGroundTruth: mask_polar and objects are both given or both None")
        for name, value in (("t_s", t_s), ("pos_ned", pos_ned), ("R_ns", R_ns), ("fan_remap", fan_remap),
                            ("_mask_polar", mask_polar), ("_objects", objects)):
            object.__setattr__(self, name, value)

    @property
    def objects_computed(self) -> bool:
        """Whether the objects' truth and the instance mask were computed for this frame."""
        return self._objects is not None

    def _require(self, what: str) -> None:
        if self._objects is None:
            raise SonarTruthNotComputedError(
                f"sonar frame at t = {self.t_s:.3f} s was rendered without its objects' ground truth, so it has no "
                f"{what}: render with truth=True, or, in a mission, give the observer that reads it "
                f"`sonar_truth = True` (see sim.events.records.MissionObserver)")

    @property
    def mask_polar(self) -> NDArray[np.int16]:
        """(n_beams, n_bins) int16 object id per beam and range bin.

        Raises:
            SonarTruthNotComputedError: the frame was rendered without its objects' truth.
        """
        self._require("mask_polar")
        return self._mask_polar

    @property
    def objects(self) -> tuple[SonarObjectTruth, ...]:
        """One record per scene object asked for.

        Raises:
            SonarTruthNotComputedError: the frame was rendered without its objects' truth.
        """
        self._require("objects")
        return self._objects

    @cached_property
    def mask_fan(self) -> NDArray[np.int16]:
        """(height_px, width_px) labels in the fan image, remapped on first access.

        Raises:
            ValueError: the sonar has no fan image.
            SonarTruthNotComputedError: the frame was rendered without its objects' truth.
        """
        if self.fan_remap is None:
            raise ValueError("this sonar frame has no fan image")
        return self.fan_remap.labels(self.mask_polar, fill=BACKGROUND_ID)

    def object(self, object_id: int) -> SonarObjectTruth:
        """The record of ``object_id``.

        Raises:
            KeyError: the object is not in this frame's truth.
            SonarTruthNotComputedError: the frame was rendered without its objects' truth.
        """
        for o in self.objects:
            if o.id == object_id:
                return o
        raise KeyError(f"object {object_id} not in this frame's truth")


def label_bins(segments: EchoSegments, n_lines: int, n_bins: int
               ) -> tuple[NDArray[np.int16], dict[int, tuple[int, int, int, int]]]:
    """Label each (line, bin) with the object whose echo energy there is the strongest.

    Args:
        segments: the echo intervals (:func:`sim.sensors.sonar.echo_lines.echo_segments`).
        n_lines, n_bins: the label image's shape.

    Returns:
        ``(mask, extents)``: mask (n_lines, n_bins) int16, :data:`BACKGROUND_ID` where no object
        wins; extents ``{object id: (line0, line1, bin0, bin1)}`` (inclusive) of each object
        that wins at least one bin. Objects compete only with each other: a bin where an
        object has any energy is labelled with it, whatever the seabed there.
    """
    rows, ua, ub, energy, obj = segments.line, segments.u0, segments.u1, segments.energy, segments.obj
    mask = np.full((n_lines, n_bins), BACKGROUND_ID, dtype=np.int16)
    extents: dict[int, tuple[int, int, int, int]] = {}
    ids = np.unique(obj[obj >= 0])
    windows = []
    for k in ids:
        sel = obj == k
        r, ua_k, ub_k = rows[sel], ua[sel], ub[sel]
        k0 = min(max(math.floor(min(ua_k.min(), ub_k.min())), 0), n_bins - 1)  # np.clip's, on scalars
        k1 = min(max(math.floor(max(ua_k.max(), ub_k.max())), k0), n_bins - 1)
        windows.append((k, sel, r, ua_k, ub_k, int(r.min()), int(r.max()), k0, k1))
    if windows:
        # strongest object per bin, over the union of the objects' windows only
        u_c0, u_k0 = min(w[5] for w in windows), min(w[7] for w in windows)
        u_c1, u_k1 = max(w[6] for w in windows), max(w[8] for w in windows)
        best_u = np.zeros((u_c1 - u_c0 + 1, u_k1 - u_k0 + 1))
        for k, sel, r, ua_k, ub_k, c0, c1, k0, k1 in windows:
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
    return mask, extents


def centroid_polar(centroid_ned: FloatArray, origin_ned: FloatArray, R_ns: FloatArray) -> tuple[float, float, float]:
    """(slant range m, azimuth rad, elevation rad) of a NED point seen from a sonar at
    ``origin_ned`` (3,) with sonar->NED rotation ``R_ns`` (3, 3)."""
    p_s = R_ns.T @ (np.asarray(centroid_ned, dtype=float) - origin_ned)
    r, a, e = sonar_to_spherical(p_s)
    return float(r), float(a), float(e)


def visible_fraction(caster: RayCaster, object_id: int, origin_ned: FloatArray, dirs_ned: FloatArray,
                     first_obj: NDArray[np.int64], n_hit: int, window_near_m: float, window_far_m: float,
                     max_range_m: float, ray_spacing_rad: float, *, rows: NDArray[np.bool_] | None = None,
                     sphere: tuple[FloatArray, float] | None = None) -> float:
    """Fraction of object ``object_id`` that the rays see unoccluded.

    Args:
        caster: the scene; without ``cast_isolated`` (an
            :class:`sim.sensors.raycast.IsolatingRayCaster`) the fraction is unknown (NaN).
        object_id: the object.
        origin_ned: (3,) ray origin.
        dirs_ned: (N, 3) unit directions of the rays of the frame.
        first_obj: (N,) object id of each ray's first hit.
        n_hit: how many of the rays hit ``object_id`` first inside the range window.
        window_near_m, window_far_m: the range window (m).
        max_range_m: cast range (m).
        ray_spacing_rad: angular ray spacing; the object's bounding cone is widened by it.
        rows: (N,) the rays to count (default all), so a caller need not copy a subset out.
        sphere: the object's bounding sphere (centre (3,) NED m, radius m) if already known
            (default: asked of the caster).

    Returns:
        ``n_hit / (rays that hit the object alone inside the window)`` in [0, 1]; 0 when no ray
        sees it first, NaN when the caster cannot isolate objects.
    """
    if not hasattr(caster, "cast_isolated"):
        return float("nan")
    if n_hit == 0:
        return 0.0  # no first hit in the window: 0 whatever the isolated count
    centre, radius = caster.object_bounding_sphere(object_id) if sphere is None else sphere
    v = np.asarray(centre, dtype=float) - origin_ned
    dist_c = float(np.linalg.norm(v))
    n_alone = 0
    if dist_c - radius <= window_far_m:
        if dist_c <= radius:
            cand = np.ones(len(dirs_ned), dtype=bool)
        else:
            half = np.arcsin(min(1.0, radius / dist_c)) + ray_spacing_rad
            cand = dirs_ned @ (v / dist_c) >= np.cos(min(half, np.pi))
        # a ray whose first hit is k hits k alone at the same range: only the others are cast
        cand &= first_obj != object_id
        if rows is not None:
            cand &= rows
        n_alone = n_hit
        if cand.any():
            d_alone = caster.cast_isolated(origin_ned, dirs_ned[cand], max_range_m, object_id)
            n_alone += int(np.count_nonzero((d_alone >= window_near_m) & (d_alone <= window_far_m)))
    frac = n_hit / n_alone if n_alone > 0 else 0.0
    return min(frac, 1.0)
