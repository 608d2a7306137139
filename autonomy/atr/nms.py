"""Non-maximum suppression of axis-aligned boxes (pure numpy)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def box_iou(boxes_a: NDArray, boxes_b: NDArray) -> NDArray[np.float64]:
    """IoU matrix between ``boxes_a`` (N, 4) and ``boxes_b`` (M, 4), xyxy -> (N, M)."""
    a = np.asarray(boxes_a, dtype=np.float64).reshape(-1, 4)
    b = np.asarray(boxes_b, dtype=np.float64).reshape(-1, 4)
    ix0 = np.maximum(a[:, None, 0], b[None, :, 0])
    iy0 = np.maximum(a[:, None, 1], b[None, :, 1])
    ix1 = np.minimum(a[:, None, 2], b[None, :, 2])
    iy1 = np.minimum(a[:, None, 3], b[None, :, 3])
    inter = np.clip(ix1 - ix0, 0.0, None) * np.clip(iy1 - iy0, 0.0, None)
    area_a = (a[:, 2] - a[:, 0]) * (a[:, 3] - a[:, 1])
    area_b = (b[:, 2] - b[:, 0]) * (b[:, 3] - b[:, 1])
    union = area_a[:, None] + area_b[None, :] - inter
    return np.where(union > 0.0, inter / np.where(union > 0.0, union, 1.0), 0.0)


def nms(boxes_xyxy: NDArray, scores: NDArray, iou_threshold: float,
        class_ids: NDArray | None = None) -> NDArray[np.int64]:
    """Greedy NMS; returns kept indices sorted by decreasing score.

    Boxes of different ``class_ids`` never suppress each other (when given).
    """
    boxes = np.asarray(boxes_xyxy, dtype=np.float64).reshape(-1, 4)
    scores = np.asarray(scores, dtype=np.float64).reshape(-1)
    if boxes.shape[0] != scores.shape[0]:
        raise ValueError(f"nms: {boxes.shape[0]} boxes but {scores.shape[0]} scores")
    if boxes.shape[0] == 0:
        return np.zeros(0, dtype=np.int64)
    if class_ids is not None:
        # Offset boxes per class so that boxes of different classes never overlap.
        cls = np.asarray(class_ids, dtype=np.float64).reshape(-1)
        span = float(np.max(boxes) - np.min(boxes)) + 1.0
        boxes = boxes + (cls * span)[:, None]
    order = np.argsort(-scores, kind="stable")
    iou = box_iou(boxes[order], boxes[order])
    n = order.size
    suppressed = np.zeros(n, dtype=bool)
    keep = []
    for i in range(n):
        if suppressed[i]:
            continue
        keep.append(order[i])
        suppressed |= iou[i] > iou_threshold
    return np.asarray(keep, dtype=np.int64)
