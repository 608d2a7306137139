"""Coarse seabed coverage map: which cells of the area a forward-looking sonar has swept."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.frames import rot_from_euler
from autonomy.localization import fls_visibility
from autonomy.sonar_frame import sonar_to_body_rotation, sonar_to_spherical
from sim.envs.area import OperatingArea


class CoverageGrid:
    """(rows, cols) grid over an area; row 0 is the southern edge, column 0 the western.

    Coverage counts the seabed the fan has swept, sampled inside each cell: a cell holds
    ``samples_per_side`` x ``samples_per_side`` points on the seabed, cell-centred (1: its
    centre only), and counts as covered once at least ``min_seen_fraction`` of them have been
    inside the sonar fan (range window, horizontal and vertical field of view) at some
    observed pose.

    Why not the centre alone: a forward-looking sonar tilted down meets the seabed only from
    its near edge outwards (about ``altitude / tan(tilt + vertical_fov / 2)`` ahead: 4.3 m at
    2 m altitude for the M900-130 at 15 deg tilt, 20 deg aperture), and sees nothing beside
    itself (beyond ``fov / 2``). Flying straight, the ground it passes over was swept by that
    near edge on the way; but a cell entered from the side or in a turn can have its centre go
    from beside the vehicle straight into the blind zone under it, so a centre-only grid never
    counts it however often the vehicle passes over it, and a planner heading for the nearest
    uncovered cell circles it for ever. Sampled, the cell is covered once the fan swept most
    of its area, which it does on the approaches of those passes.

    Args:
        area: the operating area (cells span ``lo_ne_m .. hi_ne_m``).
        shape: (rows along north, cols along east).
        seabed_depth_fn: ``depth_at(n_m, e_m) -> depth`` of the seabed, m (the survey map).
        mount_pos_body_m, mount_rpy_rad: sonar extrinsics on the hull.
        range_min_m, range_max_m, fov_rad, vertical_fov_rad: the sonar's fan.
        samples_per_side: seabed points per cell side (>= 1).
        min_seen_fraction: fraction of a cell's points the fan must have swept, in (0, 1].

    Attributes:
        centres_ned: (rows * cols, 3) cell centres on the seabed, NED m.
        samples_ned: (rows * cols, samples_per_side**2, 3) the points sampled, NED m.
        seen: (rows * cols, samples_per_side**2) bool, points the fan has swept.
        covered: (rows * cols,) bool, cells counted as covered (row-major, row 0 south).

    Raises:
        ValueError: a non-positive shape or ``samples_per_side``, or ``min_seen_fraction``
            outside (0, 1].
    """

    def __init__(self, area: OperatingArea, shape: tuple[int, int], seabed_depth_fn,
                 mount_pos_body_m: ArrayLike, mount_rpy_rad: ArrayLike, *, range_min_m: float,
                 range_max_m: float, fov_rad: float, vertical_fov_rad: float, samples_per_side: int = 3,
                 min_seen_fraction: float = 0.5) -> None:
        rows, cols = (int(v) for v in shape)
        if rows < 1 or cols < 1:
            raise ValueError(f"coverage grid shape must be positive, got {shape}")
        k = int(samples_per_side)
        if k < 1:
            raise ValueError(f"coverage samples_per_side must be >= 1, got {samples_per_side}")
        if not 0.0 < min_seen_fraction <= 1.0:
            raise ValueError(f"coverage min_seen_fraction must be in (0, 1], got {min_seen_fraction}")
        self.shape = (rows, cols)
        lo, hi = area.lo_ne_m, area.hi_ne_m
        dn, de = (hi[0] - lo[0]) / rows, (hi[1] - lo[1]) / cols

        def on_seabed(n_idx: NDArray, e_idx: NDArray) -> NDArray[np.float64]:
            """Points at fractional cell indices (0.5: a cell's centre) -> (..., 3) NED on the bed."""
            nn, ee = lo[0] + n_idx * dn, lo[1] + e_idx * de
            dd = np.asarray(seabed_depth_fn(nn, ee), dtype=float).reshape(nn.shape)
            return np.stack([nn, ee, dd], axis=-1)

        r_idx, c_idx = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
        self.centres_ned = on_seabed(r_idx + 0.5, c_idx + 0.5).reshape(-1, 3)
        sub = (np.arange(k) + 0.5) / k
        su, sv = np.meshgrid(sub, sub, indexing="ij")
        self.samples_ned = on_seabed(r_idx.reshape(-1, 1) + su.reshape(1, -1),
                                     c_idx.reshape(-1, 1) + sv.reshape(1, -1))  # (cells, k*k, 3)
        self._need = int(np.ceil(min_seen_fraction * k * k - 1e-9))
        self._mount_pos = np.asarray(mount_pos_body_m, dtype=float)
        self._mount_rpy = np.asarray(mount_rpy_rad, dtype=float)
        self._fan = dict(range_min_m=float(range_min_m), range_max_m=float(range_max_m), fov_rad=float(fov_rad),
                         vertical_fov_rad=float(vertical_fov_rad))
        self._R_bs = sonar_to_body_rotation(self._mount_rpy)
        self.seen = np.zeros(self.samples_ned.shape[:2], dtype=bool)
        self.covered = np.zeros(rows * cols, dtype=bool)

    def reset(self) -> None:
        self.seen[:] = False
        self.covered[:] = False

    def _mark(self, todo: NDArray[np.intp], seen_now: NDArray[np.bool_]) -> int:
        """Add ``seen_now`` (len(todo), k*k) to the cells ``todo``; returns how many became covered."""
        self.seen[todo] |= seen_now
        new = todo[np.count_nonzero(self.seen[todo], axis=1) >= self._need]
        self.covered[new] = True
        return int(new.size)

    def observe(self, pos_ned: ArrayLike, rpy_rad: ArrayLike) -> int:
        """Mark the points inside the fan at this vehicle pose; returns how many cells became
        covered."""
        todo = np.flatnonzero(~self.covered)
        if todo.size == 0:
            return 0
        visible = fls_visibility(pos_ned, rpy_rad, self._mount_pos, self._mount_rpy, **self._fan)
        pts = self.samples_ned[todo]
        return self._mark(todo, visible(pts.reshape(-1, 3)).reshape(pts.shape[:2]))

    def observe_many(self, pos_ned: ArrayLike, rpy_rad: ArrayLike) -> int:
        """Mark the points inside the fan at any of ``K`` poses (``pos_ned`` (K, 3) m NED,
        ``rpy_rad`` (K, 3) rad); returns how many cells became covered. Same points and count
        as :meth:`observe` called on each pose in turn (the fan test of
        :func:`autonomy.localization.fls_visibility` with no margin, the same products), but
        one batched evaluation over the cells not yet covered.

        Raises:
            ValueError: ``pos_ned`` and ``rpy_rad`` not both of shape (K, 3).
        """
        pos = np.asarray(pos_ned, dtype=float)
        rpy = np.asarray(rpy_rad, dtype=float)
        if pos.ndim != 2 or pos.shape[1] != 3 or rpy.shape != pos.shape:
            raise ValueError(f"observe_many needs pos_ned and rpy_rad of shape (K, 3), got {pos.shape}, {rpy.shape}")
        todo = np.flatnonzero(~self.covered)
        if todo.size == 0 or len(pos) == 0:
            return 0
        R_nb = np.stack([rot_from_euler(*angles) for angles in rpy.tolist()])  # (K, 3, 3)
        R_ns = R_nb @ self._R_bs
        origin = pos + R_nb @ self._mount_pos  # (K, 3) sonar origin, NED
        fan = self._fan
        pts = self.samples_ned[todo].reshape(-1, 3)  # (M k*k, 3)
        # a point farther horizontally than the range from every sonar origin is out of every
        # fan (its slant range is at least that): test only the points within the range plus
        # the origins' spread of their mean origin (1 mm more for the rounding)
        mid = origin[:, :2].mean(axis=0)
        spread = float(np.max(np.hypot(origin[:, 0] - mid[0], origin[:, 1] - mid[1])))
        reach2 = (fan["range_max_m"] + spread + 1e-3) ** 2
        near = np.flatnonzero(np.square(pts[:, 0] - mid[0]) + np.square(pts[:, 1] - mid[1]) <= reach2)
        seen_any = np.zeros(len(pts), dtype=bool)
        if near.size:
            r, a, e = sonar_to_spherical((pts[near] - origin[:, None, :]) @ R_ns)  # (K, N) each
            seen = (r >= fan["range_min_m"]) & (r <= fan["range_max_m"])
            seen &= np.abs(a) <= 0.5 * fan["fov_rad"]
            seen &= np.abs(e) <= 0.5 * fan["vertical_fov_rad"]
            seen_any[near] = seen.any(axis=0)
        return self._mark(todo, seen_any.reshape(todo.size, -1))

    @property
    def fraction(self) -> float:
        return float(np.count_nonzero(self.covered)) / self.covered.size

    def as_image(self) -> NDArray[np.float32]:
        """(rows, cols) float32 in {0, 1}."""
        return self.covered.reshape(self.shape).astype(np.float32)
