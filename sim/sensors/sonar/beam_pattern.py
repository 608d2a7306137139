"""Beam patterns of a sonar's uniform line apertures (pure numpy + OpenCV).

A uniform line aperture of length ``L`` has the one-way amplitude pattern
``sinc(L sin(theta) / lambda)``; its -3 dB one-way full width is ``0.8859 lambda / L``
(small angles). The pattern is written in terms of that full width: one-way power
``sinc^2(0.8859 theta / beamwidth)``, two-way power ``sinc^4`` (Urick, *Principles of
Underwater Sound*, ch. 3; see ``docs/references.md``). First side lobe -13.26 dB one-way,
-26.5 dB two-way.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
SINC_3DB = 0.8859  # sinc^2(SINC_3DB / 2) = 0.5: one-way -3 dB at +-beamwidth/2


def two_way_beam_power(offset_rad: ArrayLike, beamwidth_rad: float) -> FloatArray:
    """Two-way power pattern ``sinc^4(SINC_3DB offset / beamwidth)`` of a uniform line aperture.

    Args:
        offset_rad: (...) angle from the beam axis (rad).
        beamwidth_rad: one-way -3 dB full width (rad).

    Returns:
        (...) power gain, 1 on axis, 0.25 (-6 dB two-way) at ``+-beamwidth_rad / 2``.
    """
    return np.sinc(SINC_3DB * np.asarray(offset_rad) / beamwidth_rad) ** 4


def azimuth_kernel(spacing_rad: float, beamwidth_rad: float, extent_beamwidths: float,
                   side_lobe_floor_db: float | None = None) -> NDArray[np.float32]:
    """Two-way azimuth pattern sampled every ``spacing_rad`` out to ``+-extent_beamwidths``
    beam widths, normalised to unit sum: (2K + 1,) float32, K = ceil(extent bw / spacing).

    ``side_lobe_floor_db`` (two-way, dB re the main lobe's peak): the pattern never falls below
    this level outside the main lobe (its first nulls), the far side-lobe plateau of a real
    array or lens (element errors, shading, scattering in the lens) where the ideal aperture's
    lobes keep falling; None: the ideal pattern."""
    half = max(int(np.ceil(extent_beamwidths * beamwidth_rad / spacing_rad)), 0)
    theta = np.arange(-half, half + 1) * spacing_rad
    k = two_way_beam_power(theta, beamwidth_rad)
    if side_lobe_floor_db is not None:
        outside = np.abs(theta) >= beamwidth_rad / SINC_3DB  # beyond the first nulls
        k = np.where(outside, np.maximum(k, 10.0 ** (0.1 * side_lobe_floor_db)), k)
    return (k / k.sum()).astype(np.float32)


def apply_azimuth_pattern(lines: NDArray[np.float32], kernel: NDArray[np.float32]) -> NDArray[np.float32]:
    """Convolve (n_lines, n_bins) echo lines across lines (azimuth) with ``kernel``.

    Lines must be evenly spaced in azimuth at the kernel's spacing; the edge lines are
    replicated beyond the field of view. A one-tap kernel returns ``lines`` itself.
    """
    if kernel.size == 1:
        return lines
    return cv2.filter2D(lines, -1, kernel.reshape(-1, 1), borderType=cv2.BORDER_REPLICATE)
