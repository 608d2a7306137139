"""The tasks' one check of an action: shape, finiteness, then the clip to [-1, 1]."""

from __future__ import annotations

import numpy as np


def checked_action(action, n_act: int, who: str) -> np.ndarray:
    """``action`` as a float array of shape ``(n_act,)``, clipped to [-1, 1].

    Raises:
        ValueError: ``action`` is not a number sequence of shape ``(n_act,)``, or holds NaN or
            an infinity (named with ``who``, e.g. ``"WaypointTask.step"``).
    """
    try:
        a = np.asarray(action, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{who}: action must be {n_act} numbers in [-1, 1], got {action!r}") from None
    if a.shape != (n_act,):
        raise ValueError(f"{who}: action must have shape ({n_act},), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{who}: action must be finite (no NaN or infinity), got {action!r}")
    return np.clip(a, -1.0, 1.0)
