"""The onboard tracking stack of paper 004: the ROI-gated sonar detector and the three filter
configurations (sonar only, USBL only, fused) run side by side on the same inputs.

Each frame the paper's contour detector (:class:`autonomy.atr.classical.ClassicalDetector`:
blur, adaptive threshold, contours clustered by union-find) gives scored clusters once (each placed at its box centre); each
sonar-using filter then keeps the clusters inside its own polar ROI (paper 004 section 4,
:func:`autonomy.tracking.roi.polar_roi`) whose size could be the target's (:func:`shape_gate`:
extent and foreground area against the configured target size, which rejects the diver's
bubble clusters that trail inside the ROI), scores them by the detector's contrast-and-size
score times ``exp(-2 d^2)`` of their normalised distance ``d`` to the ROI centre, and feeds
the best one above ``detector_score_threshold`` to the filter. Before a filter has an
estimate (no ROI) it takes the best cluster of the whole frame. The configured ``mode`` is
the primary filter (the one guidance follows); the other two run for comparison only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from autonomy.atr.classical import ClassicalDetector
from autonomy.atr.config import ClassicalAtrConfig
from autonomy.atr.detector import to_detections
from autonomy.messages import Detection, FlsFrame, NavEstimate, UsblMsg
from autonomy.tracking.config import TrackingConfig
from autonomy.tracking.roi import PolarRoi
from autonomy.tracking.tracker import TargetTracker

MODES = ("sonar", "usbl", "fused")
FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class TrackingFrameResult:
    """What the tracking stack made of one sonar frame.

    Attributes:
        t_s: ping time, s.
        candidates: every scored cluster of the detector on the frame.
        roi: mode -> polar ROI (sonar frame) at the ping time, or None (no estimate yet).
        inside: mode -> (len(candidates),) bool, candidate inside that mode's ROI (all True
            without a ROI).
        chosen: mode -> the detection fed to that mode's filter, or None.
        features: the candidates' shape cues, (N,) arrays (see
            :meth:`autonomy.atr.classical.ClassicalDetector.clusters`).
        accepted: mode -> (N,) bool, inside that mode's ROI and of the target's size
            (:func:`shape_gate`): the clusters that mode could take.
    """

    t_s: float
    candidates: tuple[Detection, ...]
    roi: dict[str, PolarRoi | None]
    inside: dict[str, NDArray[np.bool_]]
    chosen: dict[str, Detection | None]
    features: dict[str, FloatArray]
    accepted: dict[str, NDArray[np.bool_]]


def cut_by_edge(features: dict[str, FloatArray], edge_tol_m: float) -> NDArray[np.bool_]:
    """Clusters (N,) that reach the fan's boundary (``edge_gap_m <= edge_tol_m``): a target
    there may be cut by the edge of the view (its centre outside), so what the image shows of
    it is only part of it."""
    return np.asarray(features.get("edge_gap_m", np.full(len(features["extent_m"]), np.inf)), dtype=float) <= edge_tol_m


def shape_gate(features: dict[str, FloatArray], target_size_m: float, min_extent_frac: float,
               min_area_frac: float, cut: NDArray[np.bool_] | None = None) -> NDArray[np.bool_]:
    """Clusters (N,) whose size could be the target's (paper 004: candidates compared with the
    target's known size and shape): extent (longer box side) at least ``min_extent_frac x
    target_size_m`` and foreground area at least ``min_area_frac x target_size_m^2``. A breath's
    bubbles (small, dispersing scatterers) make small, sparse clusters and fail it. A cluster
    ``cut`` (N,) by the fan's edge (:func:`cut_by_edge`) shows only part of what made it: its
    size is a lower bound (censored), so the size test cannot refuse it."""
    ext = np.asarray(features["extent_m"], dtype=float)
    area = np.asarray(features["area_m2"], dtype=float)
    ok = (ext >= min_extent_frac * target_size_m) & (area >= min_area_frac * target_size_m**2)
    return ok if cut is None else ok | np.asarray(cut, dtype=bool)


def roi_score(detections: list[Detection] | tuple[Detection, ...], roi: PolarRoi | None,
              gate: NDArray[np.bool_] | None = None) -> tuple[NDArray[np.bool_], FloatArray]:
    """Inside-ROI mask (N,) and ROI-weighted scores (N,) of ``detections``: detector score
    times ``exp(-2 d^2)``, ``d`` the normalised distance to the ROI centre (0 outside the ROI
    and where ``gate`` (N,) is False)."""
    n = len(detections)
    scores = np.array([d.score for d in detections], dtype=float)
    if gate is not None:
        scores = np.where(gate, scores, 0.0)
    if roi is None or n == 0:
        return np.ones(n, dtype=bool), scores
    r = np.array([d.range_m for d in detections])
    a = np.array([d.azimuth_rad for d in detections])
    inside = roi.contains(r, a)
    d = roi.centre_distance(r, a)
    return inside, np.where(inside, scores * np.exp(-2.0 * d**2), 0.0)


class TrackingStack:
    """Three target trackers (``sonar``, ``usbl``, ``fused``) and the ROI-gated detector.

    Args:
        cfg: tracker settings; ``cfg.mode`` names the primary filter.
        atr_cfg: the contour detector's settings.
        usbl_mount_body_m, usbl_mount_rpy_rad: (3,) FRD position (m) and frame (rad) of the USBL head.
        sonar_mount_body_m, sonar_mount_rpy_rad: (3,) of the sonar head (tilt: pitch down > 0).
    """

    def __init__(self, cfg: TrackingConfig, atr_cfg: ClassicalAtrConfig, *, usbl_mount_body_m=(0.0, 0.0, 0.0),
                 usbl_mount_rpy_rad=(0.0, 0.0, 0.0), sonar_mount_body_m=(0.0, 0.0, 0.0),
                 sonar_mount_rpy_rad=(0.0, 0.0, 0.0)) -> None:
        self.cfg = cfg
        self.detector = ClassicalDetector(atr_cfg, score_threshold=0.0, class_name=cfg.transponder)
        self.trackers = {m: TargetTracker(cfg.model_copy(update={"mode": m}), usbl_mount_body_m, sonar_mount_body_m,
                                          usbl_mount_rpy_rad=usbl_mount_rpy_rad,
                                          sonar_mount_rpy_rad=sonar_mount_rpy_rad) for m in MODES}
        self.reset()

    @property
    def primary(self) -> TargetTracker:
        return self.trackers[self.cfg.mode]

    def reset(self) -> None:
        for tr in self.trackers.values():
            tr.reset()
        self._pending: list[FlsFrame | UsblMsg] = []
        self.results: list[TrackingFrameResult] = []

    @property
    def now_s(self) -> float:
        return self.primary.now_s

    def on_nav(self, nav: NavEstimate) -> list[TrackingFrameResult]:
        """Record the vehicle pose (navigation estimate) in every filter, then process the
        inputs that were waiting for a pose at their time; returns the results of the frames
        processed now."""
        for tr in self.trackers.values():
            tr.record_pose(nav.t_s, nav.pos_ned, nav.rpy_rad)
        pending, self._pending = self._pending, []
        done = []
        for msg in pending:
            if isinstance(msg, UsblMsg):
                self.on_usbl(msg)
            elif (res := self.on_frame(msg)) is not None:
                done.append(res)
        return done

    def on_usbl(self, msg: UsblMsg) -> None:
        """A USBL fix (late: applied at ``msg.t_s``); fixes of other transponders are ignored
        here (the navigation filter takes the beacon's). A fix newer than the last pose waits
        for the next one."""
        if msg.transponder == "beacon":
            return
        if self.now_s == -np.inf or 0.0 < msg.t_s - self.now_s < 1.0:  # (further ahead: refused as from the future)
            self._pending.append(msg)
            return
        for m in ("usbl", "fused"):
            self.trackers[m].on_usbl(msg)

    def on_frame(self, frame: FlsFrame, _nav: NavEstimate | None = None) -> TrackingFrameResult | None:
        """Detect on ``frame`` and feed each sonar-using filter its best in-ROI cluster; the
        result is also appended to :attr:`results`. A frame pinged after the last vehicle pose
        waits for the next pose (returns None then)."""
        if frame.t_s > self.now_s:
            self._pending.append(frame)
            return None
        geom = frame.geometry
        boxes, scores, feats = self.detector.clusters(frame.fan, geom.m_per_px, geometry=geom)
        cands = tuple(self._centre_detections(frame, boxes, scores))
        cfg = self.cfg
        cut = cut_by_edge(feats, self.detector.cfg.blur_sigma_m + geom.m_per_px)
        shape_ok = shape_gate(feats, cfg.target_size_m, cfg.min_extent_frac, cfg.min_area_frac, cut)
        rois: dict[str, PolarRoi | None] = {}
        inside: dict[str, NDArray[np.bool_]] = {}
        accepted: dict[str, NDArray[np.bool_]] = {}
        chosen: dict[str, Detection | None] = {}
        for m in MODES:
            tr = self.trackers[m]
            rois[m] = tr.roi(frame.t_s) if m != "usbl" and tr.initialised else None
            inside[m], s = roi_score(cands, rois[m], shape_ok)
            accepted[m] = inside[m] & shape_ok
            chosen[m] = None
            if m == "usbl" or not cands:
                continue
            best = int(np.argmax(s))
            if accepted[m][best] and s[best] >= cfg.detector_score_threshold:
                chosen[m] = cands[best]
                tr.on_sonar(frame.t_s, cands[best].range_m, cands[best].azimuth_rad,
                            centre_sigma_m=0.5 * cfg.target_size_m if cut[best] else 0.0)
        result = TrackingFrameResult(float(frame.t_s), cands, rois, inside, chosen, feats, accepted)
        self.results.append(result)
        return result

    def _centre_detections(self, frame: FlsFrame, boxes: FloatArray, scores: FloatArray) -> list[Detection]:
        """Detections at their box centres: a swimmer's echo spans its body (not a seabed
        object's bright leading edge, the survey ATR's reference point)."""
        dets = to_detections(frame, boxes, scores, [self.cfg.transponder] * len(scores))
        if not dets:
            return dets
        cx, cy = 0.5 * (boxes[:, 0] + boxes[:, 2]), 0.5 * (boxes[:, 1] + boxes[:, 3])
        r, a = frame.geometry.pixel_to_polar(cx, cy)
        return [Detection(d.t_s, d.class_name, d.score, d.box_xyxy_px, float(r[i]), float(a[i]))
                for i, d in enumerate(dets)]

    def estimates(self, t_s: float) -> dict[str, tuple[FloatArray, FloatArray] | None]:
        """mode -> (mean (7,), covariance (7, 7)) at ``t_s`` or None (see :meth:`TargetTracker.estimate`)."""
        return {m: tr.estimate(t_s) for m, tr in self.trackers.items()}
