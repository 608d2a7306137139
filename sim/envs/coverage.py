"""Coarse seabed coverage map: which cells of the area a forward-looking sonar has seen."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.localization import fls_visibility
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

    @property
    def fraction(self) -> float:
        return float(np.count_nonzero(self.covered)) / self.covered.size

    def as_image(self) -> NDArray[np.float32]:
        """(rows, cols) float32 in {0, 1}."""
        return self.covered.reshape(self.shape).astype(np.float32)
