"""Polar position of a detection box on the fan image.

The reference point of a box is where the ray from the sonar apex through the box centre
enters the box: the leading edge of a seabed object, its bright near side, which is the
return least affected by shadow and elevation ambiguity. Its azimuth is the box centre's
bearing; its range is the box's near range along that bearing.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from autonomy.sonar_geometry import FanGeometry


def box_reference_px(boxes_xyxy: NDArray, geometry: FanGeometry) -> NDArray[np.float64]:
    """Reference pixel (x, y) of each box (N, 4) -> (N, 2), see module docstring."""
    b = np.asarray(boxes_xyxy, dtype=np.float64).reshape(-1, 4)
    apex = np.array([geometry.apex_x_px, geometry.apex_y_px])
    centre = np.stack([(b[:, 0] + b[:, 2]) * 0.5, (b[:, 1] + b[:, 3]) * 0.5], axis=1)
    d = centre - apex  # ray apex -> centre, parameter t in [0, 1] reaches the centre
    lo = b[:, :2]
    hi = b[:, 2:]
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = (lo - apex) / d
        t1 = (hi - apex) / d
    t_near = np.where(d != 0.0, np.minimum(t0, t1), -np.inf)
    # Slab entry: latest entry over both axes; an apex inside the box gives t < 0 -> use apex.
    t_entry = np.clip(np.max(t_near, axis=1), 0.0, 1.0)
    return apex + t_entry[:, None] * d


def box_reference_polar(boxes_xyxy: NDArray, geometry: FanGeometry) -> tuple[NDArray, NDArray]:
    """(range_m (N,), azimuth_rad (N,)) of each box's reference point."""
    p = box_reference_px(boxes_xyxy, geometry)
    return geometry.pixel_to_polar(p[:, 0], p[:, 1])
