"""Waypoint manager: which straight segment the vehicle is following, and when to switch."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.guidance.los import PathErrors, path_errors


class WaypointManager:
    """Follows waypoints in order along the segments between them.

    The active segment runs from waypoint ``index - 1`` (or the position at :meth:`start`
    for the first one) to waypoint ``index``. A waypoint counts as reached when the vehicle
    is inside ``acceptance_radius_m`` of it, or has passed the line through it
    perpendicular to the segment (along-track >= segment length), so a waypoint missed
    wide of the circle does not make the vehicle loop back.

    Attributes:
        waypoints_ne_m: (n, 2) waypoints.
        reached_t_s: (n,) time each waypoint was reached, NaN until then.
        reached_pos_ne_m: (n, 2) vehicle position when each was reached.
    """

    def __init__(self, waypoints_ne_m: ArrayLike, acceptance_radius_m: float) -> None:
        wps = np.asarray(waypoints_ne_m, dtype=float)
        if wps.ndim != 2 or wps.shape[1] != 2 or wps.shape[0] < 1:
            raise ValueError(f"waypoints_ne_m must have shape (n>=1, 2), got {wps.shape}")
        if not np.all(np.isfinite(wps)):
            raise ValueError("waypoints_ne_m must be finite")
        if not acceptance_radius_m > 0.0:
            raise ValueError(f"acceptance_radius_m must be > 0, got {acceptance_radius_m}")
        self.waypoints_ne_m = wps
        self.acceptance_radius_m = float(acceptance_radius_m)
        self.index = 0
        self.reached_t_s: NDArray[np.float64] = np.full(len(wps), np.nan)
        self.reached_pos_ne_m: NDArray[np.float64] = np.full((len(wps), 2), np.nan)
        self._segment_start: NDArray[np.float64] | None = None

    def start(self, pos_ne_m: ArrayLike) -> None:
        """Begin: the first segment runs from ``pos_ne_m`` to waypoint 0."""
        self.index = 0
        self.reached_t_s[:] = np.nan
        self.reached_pos_ne_m[:] = np.nan
        self._segment_start = np.asarray(pos_ne_m, dtype=float)[:2].copy()

    @property
    def finished(self) -> bool:
        return self.index >= len(self.waypoints_ne_m)

    @property
    def segment(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Active segment (p0, p1)."""
        if self._segment_start is None:
            raise RuntimeError("WaypointManager.start() must be called first")
        if self.finished:
            raise RuntimeError("all waypoints reached")
        p0 = self._segment_start if self.index == 0 else self.waypoints_ne_m[self.index - 1]
        return p0, self.waypoints_ne_m[self.index]

    def update(self, pos_ne_m: ArrayLike, t_s: float) -> PathErrors | None:
        """Advance past reached waypoints; return errors on the active segment (None when done)."""
        pos = np.asarray(pos_ne_m, dtype=float)[:2]
        while not self.finished:
            p0, p1 = self.segment
            if np.linalg.norm(p1 - p0) < 1e-9:
                self._mark(pos, t_s)
                continue
            err = path_errors(p0, p1, pos)
            if np.linalg.norm(pos - p1) <= self.acceptance_radius_m or err.along_track_m >= err.length_m:
                self._mark(pos, t_s)
                continue
            return err
        return None

    def _mark(self, pos: NDArray[np.float64], t_s: float) -> None:
        self.reached_t_s[self.index] = t_s
        self.reached_pos_ne_m[self.index] = pos
        self.index += 1
