"""CenterNet training targets (pure numpy): Gaussian heat-maps, sizes and offsets."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True, slots=True)
class CenterNetTargets:
    """Targets for one image on the (h, w) output grid.

    ``heat`` (C, h, w) in [0, 1]; ``weight`` (h, w) 0 inside ignored boxes, else 1;
    ``size_log`` (2, h, w), ``offset`` (2, h, w) and ``reg_mask`` (h, w) set at object centres.
    """

    heat: NDArray[np.float32]
    weight: NDArray[np.float32]
    size_log: NDArray[np.float32]
    offset: NDArray[np.float32]
    reg_mask: NDArray[np.float32]


def encode_targets(boxes_xyxy: NDArray, class_ids: NDArray, ignore: NDArray, num_classes: int,
                   grid_hw: tuple[int, int], stride: int, min_sigma_cells: float = 0.7) -> CenterNetTargets:
    """Encode boxes (N, 4) in input px (pixel centres at integers, continuous extents).

    Each object puts a Gaussian with sigma = box size / 6 (at least ``min_sigma_cells``) at
    its centre cell; ignored objects (``ignore`` True) instead zero the loss weight over
    their box.
    """
    h, w = grid_hw
    heat = np.zeros((num_classes, h, w), np.float32)
    weight = np.ones((h, w), np.float32)
    size_log = np.zeros((2, h, w), np.float32)
    offset = np.zeros((2, h, w), np.float32)
    reg_mask = np.zeros((h, w), np.float32)
    ys = np.arange(h, dtype=np.float32)[:, None]
    xs = np.arange(w, dtype=np.float32)[None, :]
    for box, c, ign in zip(np.asarray(boxes_xyxy, np.float64).reshape(-1, 4), class_ids, ignore):
        bw, bh = box[2] - box[0], box[3] - box[1]
        if bw <= 0 or bh <= 0:
            continue
        cx, cy = 0.5 * (box[0] + box[2]) / stride, 0.5 * (box[1] + box[3]) / stride
        if ign:
            x0, y0 = int(np.floor(box[0] / stride)), int(np.floor(box[1] / stride))
            x1, y1 = int(np.ceil(box[2] / stride)), int(np.ceil(box[3] / stride))
            weight[max(y0, 0):max(y1 + 1, 0), max(x0, 0):max(x1 + 1, 0)] = 0.0
            continue
        ix, iy = int(np.floor(cx)), int(np.floor(cy))
        if not (0 <= ix < w and 0 <= iy < h):
            continue
        sx = max(bw / stride / 6.0, min_sigma_cells)
        sy = max(bh / stride / 6.0, min_sigma_cells)
        g = np.exp(-0.5 * (((xs - ix) / sx) ** 2 + ((ys - iy) / sy) ** 2)).astype(np.float32)
        np.maximum(heat[c], g, out=heat[c])
        heat[c, iy, ix] = 1.0
        size_log[:, iy, ix] = np.log([bw, bh])
        offset[:, iy, ix] = (cx - ix, cy - iy)
        reg_mask[iy, ix] = 1.0
    return CenterNetTargets(heat, weight, size_log, offset, reg_mask)
