"""Onboard side-scan detector: a bright highlight followed in range by an acoustic shadow.

A proud object on the seabed returns more than the seabed on its facing side and hides the
seabed behind it; the pair (highlight, then shadow further out in range) is the classical
cue of side-scan mine detection ([Reed2003] in docs/references.md; the shadow length follows
from similar triangles, ``L = g h_o / (h - h_o)`` for an object of height ``h_o`` at ground
range ``g`` under altitude ``h``). Steps per side of
a ground-range tile (:class:`autonomy.sidescan.tile_assembler.SssTileImage`):

1. normalise each range column by its median over the tile's pings (the seabed level at that
   range, removing the residual range gain), box-filter against speckle;
2. highlight pixels: at least ``highlight_ratio`` times the seabed level, beyond ``near_m``;
   blobs of them closed over ``merge_m`` and at least ``min_highlight_m2``;
3. keep a blob when at least ``min_shadow_fraction`` of the ``shadow_window_m`` just beyond it
   in range (its rows) is shadow (at most ``shadow_ratio`` times the seabed level);
4. report the blob's centroid in the tile frame (vehicle frame at the tile's last ping:
   along-track forward, across-track starboard, m) and ``pi`` of class 1 (mine-like) from the
   highlight's along-track length (a logistic at ``class_length_m``).

Speckle alone rarely gives a highlight with a shadow behind it, so the shadow test is what
keeps clutter low.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from autonomy.sidescan.config import SssDetectorConfig
from autonomy.sidescan.tile_assembler import SssTileImage

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class SssTileDetections:
    """Detections of one tile pair.

    Attributes:
        tile_index: the tile's number k; t_s: time of its last ping, s.
        ell_m: (M, 2) positions in the tile frame (along forward, across starboard), m.
        pi1: (M,) probability of class 1 (mine-like) given the detection.
        length_m: (M,) highlight along-track length, m; shadow_fraction: (M,) of the window.
    """

    tile_index: int
    t_s: float
    ell_m: FloatArray
    pi1: FloatArray
    length_m: FloatArray
    shadow_fraction: FloatArray


def _odd(n: float) -> int:
    k = max(int(round(n)), 1)
    return k if k % 2 else k + 1


class SssHighlightShadowDetector:
    """Highlight-shadow detector (see the module docstring).

    Args:
        cfg: thresholds and class model.
    """

    def __init__(self, cfg: SssDetectorConfig) -> None:
        self.cfg = cfg

    def detect(self, tile: SssTileImage) -> SssTileDetections:
        """Detections of ``tile`` (both sides), in its tile frame."""
        ells, pis, lens, fracs = [], [], [], []
        n_rows = tile.image.shape[1]
        if n_rows >= 3:
            step = np.linalg.norm(np.diff(tile.pos_ne, axis=0), axis=1)
            row_m = float(np.median(step)) if len(step) else 0.0
            row_m = row_m if row_m > 1e-3 else 0.1
            for side in (0, 1):
                for row, col, length, frac in self._side(tile, side, row_m):
                    ells.append(tile.to_tile_frame(tile.to_ned(np.array([side]), np.array([row]), np.array([col])))[0])
                    pis.append(1.0 / (1.0 + np.exp(-(length - self.cfg.class_length_m) / self.cfg.class_length_scale_m)))
                    lens.append(length)
                    fracs.append(frac)
        return SssTileDetections(tile.index, tile.t_s, np.array(ells, dtype=float).reshape(-1, 2),
                                 np.array(pis, dtype=float), np.array(lens, dtype=float), np.array(fracs, dtype=float))

    def _side(self, tile: SssTileImage, side: int, row_m: float) -> list[tuple[float, float, float, float]]:
        cfg, b = self.cfg, tile.bin_size_m
        img = tile.image[side].astype(np.float32)
        level = np.maximum(np.median(img, axis=0), 1.0)
        norm = cv2.blur(img / level[None, :], (_odd(cfg.smooth_range_m / b), _odd(cfg.smooth_along_m / row_m)))
        rows = np.arange(img.shape[0])
        g = tile.ground_range_m(np.arange(img.shape[1])[None, :], rows[:, None])
        bright = ((norm >= cfg.highlight_ratio) & (g >= cfg.near_m)).astype(np.uint8)
        dark = norm <= cfg.shadow_ratio
        k = cv2.getStructuringElement(cv2.MORPH_RECT, (_odd(cfg.merge_m / b), _odd(cfg.merge_m / row_m)))
        n, lab, stats, cent = cv2.connectedComponentsWithStats(cv2.morphologyEx(bright, cv2.MORPH_CLOSE, k), 8)
        win = max(int(round(cfg.shadow_window_m / b)), 1)
        out = []
        for i in range(1, n):
            x, y, w, h, _ = stats[i]
            mask = (lab[y:y + h, x:x + w] == i) & (bright[y:y + h, x:x + w] > 0)
            if mask.sum() * b * row_m < cfg.min_highlight_m2:
                continue
            far = x + w
            if far + win > img.shape[1]:
                continue
            frac = float(dark[y:y + h, far:far + win].mean())
            if frac < cfg.min_shadow_fraction:
                continue
            out.append((float(cent[i][1]), float(cent[i][0]), float(h * row_m), frac))
        return out
