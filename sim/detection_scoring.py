"""Score ATR detections on one frame against the frame's ground truth (pure numpy)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray


def box_iou(a_xyxy: NDArray, b_xyxy: NDArray) -> NDArray[np.float64]:
    """IoU matrix between (n, 4) and (m, 4) boxes."""
    a = np.asarray(a_xyxy, dtype=float).reshape(-1, 4)
    b = np.asarray(b_xyxy, dtype=float).reshape(-1, 4)
    x0 = np.maximum(a[:, None, 0], b[None, :, 0])
    y0 = np.maximum(a[:, None, 1], b[None, :, 1])
    x1 = np.minimum(a[:, None, 2], b[None, :, 2])
    y1 = np.minimum(a[:, None, 3], b[None, :, 3])
    inter = np.clip(x1 - x0, 0, None) * np.clip(y1 - y0, 0, None)
    area_a = (a[:, 2] - a[:, 0]) * (a[:, 3] - a[:, 1])
    area_b = (b[:, 2] - b[:, 0]) * (b[:, 3] - b[:, 1])
    union = area_a[:, None] + area_b[None, :] - inter
    return np.where(union > 0, inter / np.maximum(union, 1e-12), 0.0)


def match_detections(
    det_boxes_xyxy: NDArray, det_scores: Sequence[float], gt_boxes_xyxy: NDArray, iou_threshold: float = 0.3
) -> NDArray[np.int64]:
    """Greedy one-to-one matching by descending score (COCO style).

    Returns:
        (n_det,) index of the matched ground-truth box, or -1 for a false detection.
    """
    n_det = len(det_scores)
    out = np.full(n_det, -1, dtype=np.int64)
    if n_det == 0 or len(gt_boxes_xyxy) == 0:
        return out
    iou = box_iou(det_boxes_xyxy, gt_boxes_xyxy)
    taken = np.zeros(iou.shape[1], dtype=bool)
    for i in np.argsort(-np.asarray(det_scores, dtype=float), kind="stable"):
        cand = np.where(~taken, iou[i], -1.0)
        j = int(np.argmax(cand))
        if cand[j] >= iou_threshold:
            out[i] = j
            taken[j] = True
    return out
