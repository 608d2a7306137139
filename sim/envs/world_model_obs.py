"""Fixed-size summaries of the PMHA world model and its scoring against the true targets."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from autonomy.world_model.anchor import CLASS_NAMES

_COV_IDX = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))
ANCHOR_FEATURES = ("n_m", "e_m", "d_m", "cov_nn", "cov_ne", "cov_nd", "cov_ee", "cov_ed", "cov_dd",
                   *(f"p_{c}" for c in CLASS_NAMES), "existence")
POS_LIMIT_M = 200.0
COV_LIMIT_M2 = 100.0


def anchor_bounds(k: int) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """(k, F) lower and upper bounds of :func:`anchor_table` rows."""
    n_cls = len(CLASS_NAMES)
    lo = np.array([-POS_LIMIT_M] * 3 + [0.0, -COV_LIMIT_M2, -COV_LIMIT_M2, 0.0, -COV_LIMIT_M2, 0.0]
                  + [0.0] * (n_cls + 1), dtype=np.float32)
    hi = np.array([POS_LIMIT_M] * 3 + [COV_LIMIT_M2] * 6 + [1.0] * (n_cls + 1), dtype=np.float32)
    return np.tile(lo, (k, 1)), np.tile(hi, (k, 1))


def anchor_table(objects: Sequence, k: int, origin_ned: NDArray) -> tuple[NDArray[np.float32], NDArray[np.int8]]:
    """Top-``k`` world objects as a (k, F) float32 table (features :data:`ANCHOR_FEATURES`,
    position relative to ``origin_ned``) and a (k,) mask (1 = row holds an object).

    Objects are ranked by existence probability, then supporting detections, then id;
    values are clipped to :func:`anchor_bounds`.
    """
    table = np.zeros((k, len(ANCHOR_FEATURES)), dtype=np.float32)
    mask = np.zeros(k, dtype=np.int8)
    ranked = sorted(objects, key=lambda o: (-o.existence_probability, -o.n_detections, o.id))[:k]
    for i, o in enumerate(ranked):
        cov = np.asarray(o.cov_ned, dtype=float)
        row = [*(np.asarray(o.pos_ned, dtype=float) - origin_ned), *(cov[a, b] for a, b in _COV_IDX),
               *np.asarray(o.class_pmf, dtype=float), float(o.existence_probability)]
        table[i] = row
        mask[i] = 1
    lo, hi = anchor_bounds(k)
    return np.clip(np.nan_to_num(table), lo, hi), mask


def match_new_targets(objects: Sequence, targets_ned: NDArray, found: NDArray[np.bool_], radius_m: float) -> int:
    """Mark true targets (``targets_ned`` (T, 3)) that some world object now lies within
    ``radius_m`` of (3-D); each object confirms at most one target, nearest first.
    Updates ``found`` (T,) in place and returns how many targets became found."""
    if len(targets_ned) == 0 or not objects:
        return 0
    n_new = 0
    for o in objects:
        d = np.linalg.norm(targets_ned - np.asarray(o.pos_ned, dtype=float), axis=1)
        d[found] = np.inf
        j = int(np.argmin(d))
        if d[j] <= radius_m:
            found[j] = True
            n_new += 1
    return n_new
