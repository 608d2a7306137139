"""Classical contour detector after paper 004 (blur, adaptive threshold, union-find clusters).

Steps on the fan image:
1. Gaussian blur (sigma in metres -> px) removes speckle.
2. Adaptive mean threshold: a pixel is foreground when brighter than the mean of its
   neighbourhood plus an offset.
3. External contours of the foreground; contours whose boxes are closer than
   ``cluster_distance_m`` are merged with a union-find (a target's highlight often breaks up).
4. Each cluster is scored from its contrast against the local background, how close its
   extent is to the expected target size, and (optionally) its distance to an ROI centre.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from autonomy.atr.config import ClassicalAtrConfig
from autonomy.atr.detector import check_frame, to_detections
from autonomy.atr.union_find import UnionFind
from autonomy.messages import Detection, FlsFrame
from autonomy.sonar_geometry import FanGeometry

_FEATURES = ("extent_m", "minor_m", "area_m2", "fill", "n_contours", "edge_gap_m")


def fan_edge_gap_m(geometry: FanGeometry, x_px: NDArray, y_px: NDArray) -> NDArray[np.float64]:
    """Distance (m) of fan pixels (x, y) (k,) to the nearest boundary of the fan: its two
    side edges (``r sin(fov / 2 - |azimuth|)``) and its near and far range arcs; negative
    outside the fan."""
    r, a = geometry.pixel_to_polar(x_px, y_px)
    side = r * np.sin(0.5 * geometry.fov_rad - np.abs(a))
    return np.minimum(side, np.minimum(r - geometry.range_min_m, geometry.range_max_m - r))


def _box_gaps_px(boxes: NDArray) -> NDArray[np.float64]:
    """Pairwise gap (N, N) between xyxy boxes in px (0 where they overlap)."""
    dx = np.maximum(0.0, np.maximum(boxes[:, None, 0] - boxes[None, :, 2], boxes[None, :, 0] - boxes[:, None, 2]))
    dy = np.maximum(0.0, np.maximum(boxes[:, None, 1] - boxes[None, :, 3], boxes[None, :, 1] - boxes[:, None, 3]))
    return np.hypot(dx, dy)


class ClassicalDetector:
    """Paper-004 contour detector. ``class_name`` labels every detection."""

    def __init__(self, cfg: ClassicalAtrConfig = ClassicalAtrConfig(), score_threshold: float = 0.5,
                 class_name: str = "opi", max_detections: int = 50) -> None:
        self.cfg = cfg
        self.score_threshold = float(score_threshold)
        self.class_name = class_name
        self.class_names: tuple[str, ...] = (class_name,)
        self.max_detections = int(max_detections)

    def candidates(self, fan: NDArray[np.uint8], m_per_px: float,
                   roi_centre_px: tuple[float, float] | None = None
                   ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """All scored clusters: boxes (N, 4) fan px xyxy, scores (N,) in [0, 1]."""
        boxes, scores, _ = self.clusters(fan, m_per_px, roi_centre_px)
        return boxes, scores

    def clusters(self, fan: NDArray[np.uint8], m_per_px: float,
                 roi_centre_px: tuple[float, float] | None = None, geometry: FanGeometry | None = None
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64], dict[str, NDArray[np.float64]]]:
        """All scored clusters with their shape cues (paper 004: a cluster is compared with the
        target's known size and shape): boxes (N, 4) fan px xyxy, scores (N,) in [0, 1], and
        (N,) arrays ``extent_m`` (longer box side), ``minor_m`` (shorter box side),
        ``area_m2`` (foreground area of its contours), ``fill`` (foreground fraction of the box),
        ``n_contours`` (contours merged into it) and ``edge_gap_m`` (smallest distance of its
        contours to the fan's boundary, :func:`fan_edge_gap_m`, with the fan ``geometry``;
        inf without): a cluster at the boundary may be a target cut by the edge of the view,
        whose extent and area are then only lower bounds."""
        cfg = self.cfg
        empty = (np.zeros((0, 4)), np.zeros(0), {k: np.zeros(0) for k in _FEATURES})
        sigma_px = max(cfg.blur_sigma_m / m_per_px, 0.3)
        blurred = cv2.GaussianBlur(fan, (0, 0), sigmaX=sigma_px)
        win = int(round(cfg.threshold_window_m / m_per_px)) | 1
        win = max(win, 3)
        binary = cv2.adaptiveThreshold(blurred, 255, cv2.ADAPTIVE_THRESH_MEAN_C, cv2.THRESH_BINARY,
                                       win, -float(cfg.threshold_offset))
        contours, _ = cv2.findContours(binary, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        if not contours:
            return empty
        rects = np.array([cv2.boundingRect(c) for c in contours], dtype=np.float64)  # x, y, w, h
        boxes = np.stack([rects[:, 0], rects[:, 1], rects[:, 0] + rects[:, 2] - 1,
                          rects[:, 1] + rects[:, 3] - 1], axis=1)
        # Ignore specks smaller than a quarter of the minimum size before clustering.
        min_px = cfg.min_size_m / m_per_px
        big = np.maximum(rects[:, 2], rects[:, 3]) >= 0.25 * min_px
        boxes = boxes[big]
        if geometry is not None and boxes.shape[0]:
            kept = [c.reshape(-1, 2) for c, b in zip(contours, big) if b]
            pts = np.concatenate(kept).astype(np.float64)
            owner = np.repeat(np.arange(len(kept)), [len(c) for c in kept])
            gap_contour = np.full(len(kept), np.inf)
            np.minimum.at(gap_contour, owner, fan_edge_gap_m(geometry, pts[:, 0], pts[:, 1]))
        else:
            gap_contour = np.full(boxes.shape[0], np.inf)
        areas = np.array([float(np.count_nonzero(binary[int(y0):int(y1) + 1, int(x0):int(x1) + 1]))
                          for x0, y0, x1, y1 in boxes]) if boxes.shape[0] else np.zeros(0)
        if boxes.shape[0] == 0:
            return empty
        uf = UnionFind(boxes.shape[0])
        gaps = _box_gaps_px(boxes)
        ii, jj = np.nonzero(np.triu(gaps <= cfg.cluster_distance_m / m_per_px, k=1))
        for i, j in zip(ii.tolist(), jj.tolist()):
            uf.union(i, j)
        lab = uf.labels()
        n = int(lab.max()) + 1
        cboxes = np.zeros((n, 4))
        for k in range(n):
            sel = boxes[lab == k]
            cboxes[k] = [sel[:, 0].min(), sel[:, 1].min(), sel[:, 2].max(), sel[:, 3].max()]
        n_contours = np.bincount(lab, minlength=n).astype(float)
        area_px = np.bincount(lab, weights=areas, minlength=n)  # (overlapping boxes may count twice)
        edge_gap_m = np.full(n, np.inf)
        np.minimum.at(edge_gap_m, lab, gap_contour)
        w_px, h_px = cboxes[:, 2] - cboxes[:, 0] + 1, cboxes[:, 3] - cboxes[:, 1] + 1
        extent_m = np.maximum(w_px, h_px) * m_per_px
        ok = (extent_m >= cfg.min_size_m) & (extent_m <= cfg.max_size_m)
        if not ok.any():
            return empty
        feats = {"extent_m": extent_m[ok], "minor_m": np.minimum(w_px, h_px)[ok] * m_per_px,
                 "area_m2": area_px[ok] * m_per_px**2,
                 "fill": np.minimum(area_px[ok] / (w_px[ok] * h_px[ok]), 1.0), "n_contours": n_contours[ok],
                 "edge_gap_m": edge_gap_m[ok]}
        cboxes, extent_m = cboxes[ok], extent_m[ok]
        scores = self._score(blurred, binary, cboxes, extent_m, m_per_px, roi_centre_px)
        return cboxes, scores, feats

    def _score(self, blurred: NDArray, binary: NDArray, boxes: NDArray, extent_m: NDArray,
               m_per_px: float, roi_centre_px: tuple[float, float] | None) -> NDArray[np.float64]:
        cfg = self.cfg
        h, w = blurred.shape
        margin = int(round(cfg.threshold_window_m / m_per_px))
        contrast = np.zeros(boxes.shape[0])
        for k, (x0, y0, x1, y1) in enumerate(boxes.astype(int)):
            inner = blurred[y0:y1 + 1, x0:x1 + 1]
            fg = binary[y0:y1 + 1, x0:x1 + 1] > 0
            ox0, oy0 = max(0, x0 - margin), max(0, y0 - margin)
            ox1, oy1 = min(w, x1 + 1 + margin), min(h, y1 + 1 + margin)
            outer = blurred[oy0:oy1, ox0:ox1].astype(np.float64)
            ring_sum = outer.sum() - inner.sum()
            ring_n = outer.size - inner.size
            bg = ring_sum / ring_n if ring_n > 0 else float(outer.mean())
            contrast[k] = float(inner[fg].mean()) - bg if fg.any() else 0.0
        s_contrast = 1.0 - np.exp(-np.clip(contrast, 0.0, None) / cfg.contrast_scale)
        s_size = np.exp(-0.5 * (np.log(extent_m / cfg.expected_size_m) / np.log(2.0)) ** 2)
        score = s_contrast * (0.5 + 0.5 * s_size)
        if roi_centre_px is not None and cfg.roi_radius_m is not None:
            cx = 0.5 * (boxes[:, 0] + boxes[:, 2])
            cy = 0.5 * (boxes[:, 1] + boxes[:, 3])
            d_m = np.hypot(cx - roi_centre_px[0], cy - roi_centre_px[1]) * m_per_px
            score = score * np.exp(-0.5 * (d_m / cfg.roi_radius_m) ** 2)
        return score

    def detect_boxes(self, fan: NDArray[np.uint8], m_per_px: float, score_threshold: float | None = None,
                     roi_centre_px: tuple[float, float] | None = None
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        thr = self.score_threshold if score_threshold is None else float(score_threshold)
        boxes, scores = self.candidates(fan, m_per_px, roi_centre_px)
        order = np.argsort(-scores, kind="stable")
        order = order[scores[order] >= thr][: self.max_detections]
        return boxes[order], scores[order]

    def detect(self, frame: FlsFrame, score_threshold: float | None = None,
               roi_centre_px: tuple[float, float] | None = None) -> list[Detection]:
        """Detections on ``frame``; ``roi_centre_px`` (x, y) weights candidates by distance to it."""
        check_frame(frame, None, source="classical detector")
        boxes, scores = self.detect_boxes(frame.fan, frame.geometry.m_per_px, score_threshold, roi_centre_px)
        return to_detections(frame, boxes, scores, [self.class_name] * len(scores))
