"""Matching detections to ground-truth boxes in one frame (greedy by score, IoU threshold).

Two thresholds, one name each: :data:`DETECTION_MATCH_IOU` for dataset evaluation (the
COCO AP50 criterion) and :data:`MISSION_DETECTION_MATCH_IOU` for the in-mission detection
figures, where a target seen at long range spans few pixels and a box that overlaps a
third of it has found it.
"""

from __future__ import annotations

import numpy as np

from autonomy.atr.nms import box_iou

DETECTION_MATCH_IOU = 0.5  # PASCAL VOC / COCO AP50 criterion
MISSION_DETECTION_MATCH_IOU = 0.3


def match_frame(det_boxes: np.ndarray, det_scores: np.ndarray, gt_boxes: np.ndarray, gt_crowd: np.ndarray,
                iou_threshold: float = DETECTION_MATCH_IOU) -> tuple[np.ndarray, np.ndarray]:
    """Greedy matching by decreasing score.

    Args:
        det_boxes: (N, 4) detection boxes, xyxy px. det_scores: (N,) scores.
        gt_boxes: (M, 4) ground-truth boxes, xyxy px. gt_crowd: (M,) bool, objects that
            are present but not expected to be detected (matches to them are ignored).
        iou_threshold: least IoU for a match.

    Returns:
        (det_state (N,) with 1 true, 0 false, -1 ignored; gt_matched (M,) bool).
    """
    n, m = det_boxes.shape[0], gt_boxes.shape[0]
    state = np.zeros(n, dtype=np.int64)
    matched = np.zeros(m, dtype=bool)
    if n == 0:
        return state, matched
    iou = box_iou(det_boxes, gt_boxes) if m else np.zeros((n, 0))
    for i in np.argsort(-det_scores, kind="stable"):
        cand = np.where(~matched & ~gt_crowd & (iou[i] >= iou_threshold), iou[i], -1.0)
        if m and cand.max() >= iou_threshold:
            j = int(np.argmax(cand))
            matched[j] = True
            state[i] = 1
        elif m and np.any(gt_crowd & (iou[i] >= iou_threshold)):
            state[i] = -1
    return state, matched
