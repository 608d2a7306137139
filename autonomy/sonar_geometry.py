"""Geometry of a forward-looking sonar fan image (pure numpy).

The fan image shows the sonar's (range, azimuth) plane, apex at the bottom centre,
forward up, starboard to the right. Azimuth is positive to starboard. Pixel
coordinates are (x = column, y = row), continuous, with pixel centres at integers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray


@dataclass(frozen=True, slots=True)
class FanGeometry:
    """Mapping between fan-image pixels and polar (range, azimuth).

    Attributes:
        width_px, height_px: image size.
        range_min_m, range_max_m: displayed range window.
        fov_rad: full horizontal field of view.
        m_per_px: metric size of one pixel.
        apex_x_px, apex_y_px: pixel position of the sonar head (may lie below the image).
    """

    width_px: int
    height_px: int
    range_min_m: float
    range_max_m: float
    fov_rad: float
    m_per_px: float
    apex_x_px: float
    apex_y_px: float

    @classmethod
    def fit(
        cls, width_px: int, height_px: int, range_min_m: float, range_max_m: float, fov_rad: float
    ) -> "FanGeometry":
        """Largest scale at which the fan fits a ``width_px`` x ``height_px`` image."""
        half = 0.5 * fov_rad
        lateral_m = 2.0 * range_max_m * np.sin(min(half, 0.5 * np.pi))
        near_m = range_min_m * np.cos(half) if half < 0.5 * np.pi else -range_max_m * np.cos(half)
        depth_m = range_max_m - near_m
        m_per_px = max(lateral_m / (width_px - 1), depth_m / (height_px - 1))
        apex_x = 0.5 * (width_px - 1)
        apex_y = (height_px - 1) + near_m / m_per_px
        return cls(int(width_px), int(height_px), float(range_min_m), float(range_max_m),
                   float(fov_rad), float(m_per_px), float(apex_x), float(apex_y))

    def polar_to_pixel(self, range_m: ArrayLike, azimuth_rad: ArrayLike) -> tuple[NDArray, NDArray]:
        """(range, azimuth) -> continuous pixel (x, y)."""
        r = np.asarray(range_m, dtype=float)
        a = np.asarray(azimuth_rad, dtype=float)
        x = self.apex_x_px + r * np.sin(a) / self.m_per_px
        y = self.apex_y_px - r * np.cos(a) / self.m_per_px
        return x, y

    def pixel_to_polar(self, x_px: ArrayLike, y_px: ArrayLike) -> tuple[NDArray, NDArray]:
        """Continuous pixel (x, y) -> (range m, azimuth rad)."""
        dx = (np.asarray(x_px, dtype=float) - self.apex_x_px) * self.m_per_px
        dy = (self.apex_y_px - np.asarray(y_px, dtype=float)) * self.m_per_px
        return np.hypot(dx, dy), np.arctan2(dx, dy)

    def inside(self, range_m: ArrayLike, azimuth_rad: ArrayLike) -> NDArray[np.bool_]:
        r = np.asarray(range_m)
        a = np.asarray(azimuth_rad)
        return (r >= self.range_min_m) & (r <= self.range_max_m) & (np.abs(a) <= 0.5 * self.fov_rad)
