"""Mission NED frame <-> WGS-84 latitude / longitude / height, through ``pymap3d``.

The mission's local NED frame is the tangent plane at a geodetic origin (latitude,
longitude, ellipsoidal height of the sea surface there). ``pymap3d`` (a small pure-Python
library) does the WGS-84 conversions: geodetic -> ECEF is closed form, ECEF -> geodetic is
its exact (non-iterative) inverse, and the NED axes are the local north, east and down of
the origin. Depth in messages is ``origin.height_m - height``: metres below the origin's
ellipsoidal height along the local normal. It differs from the NED down coordinate by the
Earth's curvature, about ``horizontal_distance^2 / (2 R)`` (2 cm at 500 m), so round trips
go through these functions rather than reading depth as ``d``.

Paper 000 section VII (docs/references.md [P000]) reports detections as latitude, longitude
and depth; the default origin is the CSSN basin in La Spezia ([CSSN]).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pymap3d
from numpy.typing import ArrayLike, NDArray
from pydantic import Field

from autonomy.config_base import StrictModel

FloatArray = NDArray[np.float64]

#: Default origin: the CSSN harbour basin, San Bartolomeo, La Spezia, Italy (docs/references.md
#: [CSSN]; our reading of the waterfront's position, good to a few hundred metres).
CSSN_LAT_DEG = 44.0935
CSSN_LON_DEG = 9.8600


class GeodeticOrigin(StrictModel):
    """The mission NED origin on the WGS-84 ellipsoid (``world.origin`` of a scenario).

    Attributes:
        lat_deg: geodetic latitude, deg, in [-89.9, 89.9] (the NED frame is undefined at a pole).
        lon_deg: longitude, deg east, in [-180, 180].
        height_m: ellipsoidal height of the origin (the sea surface there), m. 0 by default:
            the geoid undulation (tens of metres in the Ligurian Sea) is not modelled, and
            every depth is relative to this height, so it cancels in the mission.
    """

    lat_deg: float = Field(CSSN_LAT_DEG, ge=-89.9, le=89.9, description="geodetic latitude, deg")
    lon_deg: float = Field(CSSN_LON_DEG, ge=-180.0, le=180.0, description="longitude, deg east")
    height_m: float = Field(0.0, ge=-500.0, le=9000.0, description="ellipsoidal height of the NED origin, m")


def ned_to_geodetic(pos_ned: ArrayLike, origin: GeodeticOrigin) -> FloatArray:
    """Geodetic coordinates of NED points.

    Args:
        pos_ned: (..., 3) north, east, down, m, in the mission frame of ``origin``.
        origin: the frame's origin.

    Returns:
        (..., 3) latitude (deg), longitude (deg east), ellipsoidal height (m), WGS-84.

    Raises:
        ValueError: the last axis is not 3 long.
    """
    return _convert(pymap3d.ned2geodetic, pos_ned, origin, "pos_ned")


def geodetic_to_ned(lat_lon_h: ArrayLike, origin: GeodeticOrigin) -> FloatArray:
    """NED coordinates (m) of (..., 3) latitude (deg), longitude (deg), ellipsoidal height (m).

    Raises:
        ValueError: the last axis is not 3 long.
    """
    return _convert(pymap3d.geodetic2ned, lat_lon_h, origin, "lat_lon_h")


def _convert(fn: Callable[..., tuple], values: ArrayLike, origin: GeodeticOrigin, name: str) -> FloatArray:
    """Apply a pymap3d conversion taking three coordinates and the origin to (..., 3) values."""
    v = _last_axis3(values, name)
    out = fn(v[..., 0], v[..., 1], v[..., 2], origin.lat_deg, origin.lon_deg, origin.height_m)
    return np.stack(np.broadcast_arrays(*out), axis=-1).astype(float)


def ned_to_lat_lon_depth(pos_ned: ArrayLike, origin: GeodeticOrigin) -> FloatArray:
    """(..., 3) latitude (deg), longitude (deg), depth (m below the origin's height) of NED points."""
    g = ned_to_geodetic(pos_ned, origin)
    g[..., 2] = origin.height_m - g[..., 2]
    return g


def lat_lon_depth_to_ned(lat_lon_depth: ArrayLike, origin: GeodeticOrigin) -> FloatArray:
    """NED points (..., 3), m, of latitude (deg), longitude (deg), depth (m below the origin's height)."""
    g = np.array(_last_axis3(lat_lon_depth, "lat_lon_depth"), dtype=float)
    g[..., 2] = origin.height_m - g[..., 2]
    return geodetic_to_ned(g, origin)


def _last_axis3(values: ArrayLike, name: str) -> FloatArray:
    a = np.asarray(values, dtype=float)
    if a.ndim == 0 or a.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3), got {a.shape}")
    return a
