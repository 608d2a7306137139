"""Janus DVL beam geometry: beam directions and the velocity solution's covariance."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def janus_beam_dirs_body(beam_angle_rad: float, azimuth_offset_rad: float = np.pi / 4) -> FloatArray:
    """Unit directions (4, 3) in FRD of four beams tilted ``beam_angle_rad`` from body +z (down),
    at azimuths ``offset + k * 90 deg`` from the bow (starboard positive)."""
    az = azimuth_offset_rad + np.arange(4) * (np.pi / 2)
    s, c = np.sin(beam_angle_rad), np.cos(beam_angle_rad)
    return np.column_stack([s * np.cos(az), s * np.sin(az), np.full(4, c)])


def beam_velocity_covariance(beam_dirs: FloatArray, beam_sigma_mps: float) -> FloatArray:
    """Covariance (3, 3) of the least-squares velocity from radial beam velocities with
    independent noise ``beam_sigma_mps``: ``sigma^2 (B^T B)^-1``. ``beam_dirs`` is (n>=3, 3)."""
    B = np.asarray(beam_dirs, dtype=float)
    return beam_sigma_mps**2 * np.linalg.inv(B.T @ B)
