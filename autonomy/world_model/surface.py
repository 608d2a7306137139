"""The world model on the surface: PMHA on the detections an acoustic link delivers.

Paper 000 section VII (docs/references.md [P000]) runs the data-association world model on
the buoy, from the detections the AUV sends over the acoustic modem. Each report carries its
frame's absolute time and the detection in latitude / longitude / depth; the reports of one
sonar frame (one PMHA scan) leave the AUV together and arrive one packet after another,
seconds after the frame, some lost. :class:`SurfaceWorldModel` therefore

- converts each report into the mission frame (:meth:`DetectionReport.to_localized`), with
  the measurement time from the message, not the arrival time;
- groups reports by frame time and hands a scan to the PMHA once it is complete: a report
  of a later frame has arrived (the link delivers in sending order, so nothing of the earlier
  frame is still to come) or ``hold_s`` has passed since the frame;
- processes scans in time order; a report older than the last processed scan (it cannot be
  inserted into the hypothesis tree's past) is counted in ``n_too_late`` and dropped.

The surface does not receive the AUV's pose at each frame, nor the frames without
detections. It knows where the AUV was from its own USBL fixes (:class:`FixTrack`: a
straight-line least-squares fit of the recent fixes gives the position and course at the
frame time) and the AUV's sonar (:class:`SonarFootprint`): anchors well inside the fan so
placed (the fan shrunk by ``margin_m`` for the fix and course errors) count as visible at
that frame, so a false object the sonar kept looking at without detecting is penalised as
on board; the others, and every anchor when the track is too thin, get the PMHA's visibility
floor (detected with probability ``p_detect * visibility_floor``), so an object is never
penalised for a miss the surface cannot know about.

A scan's own reports also tell where the fan was: a detection at ``z`` means the fan covered
``z``, and the fan (metres to tens of metres across) is far larger than a detection's
uncertainty, so an anchor within the association gate of a report of the scan
(:func:`near_reports`) was in view too and is penalised if the scan does not assign it a
detection. Without this, anchors near the shrunk fan's edge sit at the visibility floor and
one object's detections, alternating between two anchors a few tenths of a metre apart, fit
a pair better than one anchor at almost no miss cost: twin objects, two confirmed anchors
for one true OPI, as the surface model once made in 3 of 10 sea-trial seeds.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from autonomy.comms.messages import DetectionReport
from autonomy.geodesy import GeodeticOrigin
from autonomy.localization.field_of_view import fls_visibility
from autonomy.localization.geolocate import LocalizedDetection
from autonomy.world_model.config import WorldModelConfig
from autonomy.world_model.pmha import PMHA, WorldObject


def unseen(points_ned: np.ndarray) -> np.ndarray:
    """Visibility for a PMHA that does not know the sonar's field of view: 0 for every point
    (the PMHA then uses its ``visibility_floor``)."""
    return np.zeros(len(points_ned))


def near_reports(reports: Sequence[LocalizedDetection], gate_mahalanobis2: float) -> Callable[[np.ndarray], np.ndarray]:
    """Visibility implied by one scan's reports: 1 for points within ``gate_mahalanobis2``
    (squared Mahalanobis distance under the report's (3, 3) NED covariance, m^2) of a report,
    else 0. ``points_ned`` (N, 3) NED m -> (N,) float."""
    Z = np.stack([np.asarray(z.pos_ned, dtype=float) for z in reports]) if reports else np.zeros((0, 3))
    W = np.stack([np.linalg.inv(np.asarray(z.cov_ned, dtype=float)) for z in reports]) if reports else np.zeros((0, 3, 3))

    def visible(points_ned: np.ndarray) -> np.ndarray:
        X = np.asarray(points_ned, dtype=float).reshape(-1, 3)
        if not len(Z):
            return np.zeros(len(X))
        d = X[:, None, :] - Z[None, :, :]  # (N, M, 3)
        m2 = np.einsum("nmi,mij,nmj->nm", d, W, d)
        return (m2 <= gate_mahalanobis2).any(axis=1).astype(float)

    return visible


class FixTrack:
    """The AUV's recent positions from the surface vehicle's USBL fixes.

    Args:
        window_s: fixes within this of a query time are fitted, s.
        min_fixes: fewer fixes in the window: no pose.
        min_travel_m: the fitted track must move this much over the window (else no course).
    """

    def __init__(self, window_s: float = 5.0, min_fixes: int = 4, min_travel_m: float = 1.0) -> None:
        self.window_s, self.min_fixes, self.min_travel_m = float(window_s), int(min_fixes), float(min_travel_m)
        self._fixes: deque[tuple[float, np.ndarray]] = deque()

    def add(self, t_s: float, pos_ned: ArrayLike) -> None:
        """A fix of the AUV at mission time ``t_s`` (in time order), (3,) NED m."""
        self._fixes.append((float(t_s), np.asarray(pos_ned, dtype=float).reshape(3)))
        while self._fixes and self._fixes[0][0] < t_s - 120.0:
            self._fixes.popleft()

    def pose_at(self, t_s: float) -> tuple[np.ndarray, float] | None:
        """``(pos_ned (3,), course_rad)`` at ``t_s`` from the least-squares straight line
        through the fixes within ``window_s``, or None (too few fixes, too little travel)."""
        near = [(t, p) for t, p in self._fixes if abs(t - t_s) <= self.window_s]
        if len(near) < self.min_fixes:
            return None
        t = np.array([f[0] for f in near]) - t_s
        P = np.stack([f[1] for f in near])
        A = np.column_stack([np.ones_like(t), t])
        coef, *_ = np.linalg.lstsq(A, P, rcond=None)  # rows: position at t_s, velocity
        vel = coef[1]
        if math.hypot(vel[0], vel[1]) * (t.max() - t.min()) < self.min_travel_m:
            return None
        return coef[0], math.atan2(vel[1], vel[0])


@dataclass(frozen=True, slots=True)
class SonarFootprint:
    """The AUV's forward-looking sonar as the surface knows it: mount (FRD m, rad), range
    window (m), horizontal and vertical fields of view (rad), and the margin (m, negative:
    shrink) by which the fan's range window and azimuth are cut for the pose errors of a
    USBL track."""

    mount_pos_body_m: tuple[float, float, float]
    mount_rpy_rad: tuple[float, float, float]
    range_min_m: float
    range_max_m: float
    fov_rad: float
    vertical_fov_rad: float | None
    margin_m: float = -2.0

    def visibility(self, pose: tuple[np.ndarray, float] | None) -> Callable[[np.ndarray], np.ndarray]:
        """The PMHA visibility of the fan at ``pose`` (position, course: level attitude along
        the course), or :func:`unseen` without a pose."""
        if pose is None:
            return unseen
        pos, course = pose
        args = (pos, (0.0, 0.0, course), self.mount_pos_body_m, self.mount_rpy_rad)
        kw = dict(range_min_m=self.range_min_m, range_max_m=self.range_max_m, fov_rad=self.fov_rad)
        # the margin cuts range and azimuth (horizontal fix and course errors); the narrow
        # vertical beam is kept as it is (depth and pitch are well known)
        inside = fls_visibility(*args, **kw, margin_m=self.margin_m)
        if self.vertical_fov_rad is None:
            return inside
        vertical = fls_visibility(*args, **kw, vertical_fov_rad=self.vertical_fov_rad)
        return lambda points_ned: inside(points_ned) & vertical(points_ned)


class SurfaceWorldModel:
    """PMHA fed with delivered detection reports, in measurement-time order.

    Args:
        cfg: the world model's config (the same as the onboard one).
        region_ned: ((3,) min, (3,) max) surveyed volume, NED m (as the onboard PMHA's).
        origin: the mission frame's geodetic origin.
        epoch_unix_s: UNIX time of mission time 0, s.
        class_names: the class table of the reports' class ids.
        hold_s: a scan is processed at the latest this long after its frame time, s.
        footprint: the AUV's sonar (None: every anchor at the visibility floor).
        track: the AUV's fixes the footprint is placed with (None: as without a footprint).

    Attributes:
        pmha: the world model.
        n_reports, n_scans, n_too_late: reports received, scans processed, reports dropped
            for arriving after a later scan was processed.
    """

    def __init__(self, cfg: WorldModelConfig, region_ned: tuple[ArrayLike, ArrayLike], origin: GeodeticOrigin,
                 epoch_unix_s: float, class_names: Sequence[str], *, hold_s: float = 10.0,
                 footprint: SonarFootprint | None = None, track: FixTrack | None = None) -> None:
        if not hold_s >= 0.0:
            raise ValueError(f"hold_s must be >= 0, got {hold_s}")
        self.pmha = PMHA(cfg, region_ned=region_ned)
        self.origin, self.epoch_unix_s = origin, float(epoch_unix_s)
        self.class_names = tuple(class_names)
        self.hold_s = float(hold_s)
        self.footprint, self.track = footprint, track
        self._pending: dict[float, list[LocalizedDetection]] = {}
        self.n_reports = self.n_scans = self.n_too_late = 0

    def receive(self, report: DetectionReport) -> None:
        """Take one delivered report (buffered until its scan is complete)."""
        self.n_reports += 1
        det = report.to_localized(self.origin, self.epoch_unix_s, self.class_names)
        t = round(det.t_s, 3)  # the message's millisecond time stamp names the frame
        if t <= self.pmha.t_s:
            self.n_too_late += 1
            return
        self._pending.setdefault(t, []).append(det)

    def flush(self, t_now_s: float, *, final: bool = False) -> int:
        """Process, in time order, the complete scans at mission time ``t_now_s``: those
        older than the newest frame received, those older than ``hold_s``, and with
        ``final`` every pending one. Returns the number of scans processed."""
        if not self._pending:
            return 0
        newest = max(self._pending)
        done = sorted(t for t in self._pending if final or t < newest or t <= t_now_s - self.hold_s)
        for t in done:
            scan = self._pending.pop(t)
            in_fan = unseen
            if self.footprint is not None and self.track is not None:
                in_fan = self.footprint.visibility(self.track.pose_at(t))
            near = near_reports(scan, self.pmha.cfg.gate_mahalanobis2)

            def visible(points_ned: np.ndarray, in_fan=in_fan, near=near) -> np.ndarray:
                return np.maximum(np.asarray(in_fan(points_ned), dtype=float), near(points_ned))

            self.pmha.update(t, scan, visible)
            self.n_scans += 1
        return len(done)

    def world_model(self) -> list[WorldObject]:
        return self.pmha.world_model()

    def to_json(self) -> dict:
        """The PMHA's JSON (:meth:`PMHA.to_json`) with the link counters."""
        out = self.pmha.to_json()
        out.update(reports_received=self.n_reports, scans=self.n_scans, reports_too_late=self.n_too_late)
        return out
