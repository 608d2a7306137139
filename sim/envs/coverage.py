"""Coarse seabed coverage map: which cells of the area a forward-looking sonar has seen."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.frames import rot_from_euler
from autonomy.localization import fls_visibility
from autonomy.sonar_frame import sonar_to_body_rotation, sonar_to_spherical
from sim.envs.area import OperatingArea


class CoverageGrid:
    """(rows, cols) grid over an area; row 0 is the southern edge, column 0 the western.

    A cell counts as covered once its centre, on the seabed, lies inside the sonar fan
    (range window, horizontal and vertical field of view) at some observed pose.

    Args:
        area: the operating area (cells span ``lo_ne_m .. hi_ne_m``).
        shape: (rows along north, cols along east).
        seabed_depth_fn: ``depth_at(n_m, e_m) -> depth`` of the seabed, m (the survey map).
        mount_pos_body_m, mount_rpy_rad: sonar extrinsics on the hull.
        range_min_m, range_max_m, fov_rad, vertical_fov_rad: the sonar's fan.
    """

    def __init__(self, area: OperatingArea, shape: tuple[int, int], seabed_depth_fn,
                 mount_pos_body_m: ArrayLike, mount_rpy_rad: ArrayLike, *, range_min_m: float,
                 range_max_m: float, fov_rad: float, vertical_fov_rad: float) -> None:
        rows, cols = (int(v) for v in shape)
        if rows < 1 or cols < 1:
            raise ValueError(f"coverage grid shape must be positive, got {shape}")
        self.shape = (rows, cols)
        lo, hi = area.lo_ne_m, area.hi_ne_m
        n = lo[0] + (np.arange(rows) + 0.5) * (hi[0] - lo[0]) / rows
        e = lo[1] + (np.arange(cols) + 0.5) * (hi[1] - lo[1]) / cols
        nn, ee = np.meshgrid(n, e, indexing="ij")
        dd = np.asarray(seabed_depth_fn(nn, ee), dtype=float).reshape(nn.shape)
        self.centres_ned = np.stack([nn, ee, dd], axis=-1).reshape(-1, 3)
        self._mount_pos = np.asarray(mount_pos_body_m, dtype=float)
        self._mount_rpy = np.asarray(mount_rpy_rad, dtype=float)
        self._fan = dict(range_min_m=float(range_min_m), range_max_m=float(range_max_m), fov_rad=float(fov_rad),
                         vertical_fov_rad=float(vertical_fov_rad))
        self._R_bs = sonar_to_body_rotation(self._mount_rpy)
        self.covered = np.zeros(rows * cols, dtype=bool)

    def reset(self) -> None:
        self.covered[:] = False

    def observe(self, pos_ned: ArrayLike, rpy_rad: ArrayLike) -> int:
        """Mark the cells inside the fan at this vehicle pose; returns how many are new."""
        visible = fls_visibility(pos_ned, rpy_rad, self._mount_pos, self._mount_rpy, **self._fan)
        seen = visible(self.centres_ned)
        new = seen & ~self.covered
        n_new = int(np.count_nonzero(new))
        if n_new:
            self.covered |= new
        return n_new

    def observe_many(self, pos_ned: ArrayLike, rpy_rad: ArrayLike) -> int:
        """Mark the cells inside the fan at any of ``K`` poses (``pos_ned`` (K, 3) m NED,
        ``rpy_rad`` (K, 3) rad); returns how many are new. Same cells and count as
        :meth:`observe` called on each pose in turn (the fan test of
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
        r, a, e = sonar_to_spherical((self.centres_ned[todo] - origin[:, None, :]) @ R_ns)  # (K, M) each
        fan = self._fan
        seen = (r >= fan["range_min_m"]) & (r <= fan["range_max_m"])
        seen &= np.abs(a) <= 0.5 * fan["fov_rad"]
        seen &= np.abs(e) <= 0.5 * fan["vertical_fov_rad"]
        new = todo[seen.any(axis=0)]
        self.covered[new] = True
        return int(new.size)

    @property
    def fraction(self) -> float:
        return float(np.count_nonzero(self.covered)) / self.covered.size

    def as_image(self) -> NDArray[np.float32]:
        """(rows, cols) float32 in {0, 1}."""
        return self.covered.reshape(self.shape).astype(np.float32)
