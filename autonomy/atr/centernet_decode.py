"""Decoding of CenterNet-style heat-map outputs into boxes (pure numpy).

Model outputs for one image, on a grid of stride ``s`` input pixels:
``heatmap`` (C, h, w) peak scores in [0, 1] (non-maxima already zeroed by the model),
``size`` (2, h, w) log of box (width, height) in input pixels, ``offset`` (2, h, w) sub-cell
offset of the centre in cells.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def decode_centernet(heatmap: NDArray, size_log: NDArray, offset: NDArray, stride: int,
                     score_threshold: float, max_detections: int
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """Peaks above ``score_threshold`` -> (boxes (N, 4) xyxy input px, scores (N,), class ids (N,)).

    At most ``max_detections`` highest peaks are returned, by decreasing score.
    """
    if heatmap.ndim != 3 or size_log.shape[0] != 2 or offset.shape[0] != 2:
        raise ValueError(f"decode_centernet: bad output shapes {heatmap.shape}, {size_log.shape}, {offset.shape}")
    c, h, w = heatmap.shape
    flat = heatmap.reshape(-1)
    idx = np.flatnonzero(flat >= score_threshold)
    if idx.size == 0:  # nothing to decode
        return np.zeros((0, 4)), np.zeros(0), np.zeros(0, dtype=np.int64)
    if idx.size > max_detections:
        idx = idx[np.argpartition(-flat[idx], max_detections - 1)[:max_detections]]
    idx = idx[np.argsort(-flat[idx], kind="stable")]
    cls, rem = np.divmod(idx, h * w)
    iy, ix = np.divmod(rem, w)
    # One gather per output for both channels; int64 cell + float32 offset -> float64 centre.
    centre = (np.stack([ix, iy], axis=1) + offset.reshape(2, -1)[:, rem].T) * stride
    half = 0.5 * np.exp(np.clip(size_log.reshape(2, -1)[:, rem], -4.0, 8.0)).T  # float32 (N, 2)
    boxes = np.concatenate([centre - half, centre + half], axis=1)
    return boxes, flat[idx].astype(np.float64), cls
