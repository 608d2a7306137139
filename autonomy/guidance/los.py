"""Lookahead-based line-of-sight (LOS) path following on straight segments (Fossen ch. 12)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike


@dataclass(frozen=True, slots=True)
class PathErrors:
    """Position of the vehicle relative to a straight segment ``p0 -> p1``.

    Attributes:
        path_angle_rad: direction of the segment (NED, clockwise from north).
        along_track_m: distance along the segment from ``p0`` (may be < 0 or > length).
        cross_track_m: signed distance off the line, positive to starboard of the path.
        length_m: segment length.
    """

    path_angle_rad: float
    along_track_m: float
    cross_track_m: float
    length_m: float


def path_errors(p0_ne_m: ArrayLike, p1_ne_m: ArrayLike, pos_ne_m: ArrayLike) -> PathErrors:
    """Along- and cross-track errors of ``pos_ne_m`` w.r.t. the segment (all NE, m)."""
    p0 = np.asarray(p0_ne_m, dtype=float)[:2]
    d = np.asarray(p1_ne_m, dtype=float)[:2] - p0
    length = float(np.hypot(d[0], d[1]))
    if length <= 0.0:
        raise ValueError("path segment has zero length")
    angle = math.atan2(d[1], d[0])
    c, s = math.cos(angle), math.sin(angle)
    rel = np.asarray(pos_ne_m, dtype=float)[:2] - p0
    along = c * rel[0] + s * rel[1]
    cross = -s * rel[0] + c * rel[1]
    return PathErrors(angle, float(along), float(cross), length)


def los_course_rad(errors: PathErrors, lookahead_m: float) -> float:
    """Desired course ``chi_d = pi_p - atan(e / Delta)``, wrapped to [-pi, pi).

    For a vehicle moving on that course at speed U the cross-track error obeys
    ``de/dt = -U e / sqrt(e^2 + Delta^2)``: it decays monotonically to 0.
    """
    if not lookahead_m > 0.0:
        raise ValueError(f"lookahead_m must be > 0, got {lookahead_m}")
    chi = errors.path_angle_rad - math.atan2(errors.cross_track_m, lookahead_m)
    return (chi + math.pi) % (2.0 * math.pi) - math.pi
