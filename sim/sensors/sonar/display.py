"""What a sonar shows: the dB display mapping of echo lines and, for a fan-shaped sonar, the
polar -> fan image resampling (pure numpy + OpenCV)."""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from autonomy.sonar_geometry import FanGeometry
from sim.sensors.sonar.fused_passes import kernels

FloatArray = NDArray[np.float64]


def to_uint8_db(intensity: NDArray[np.float32], gain_per_bin: NDArray[np.float32], gain_db: float,
                dynamic_range_db: float) -> NDArray[np.uint8]:
    """Display mapping of (n_lines, n_bins) linear intensities with a per-bin gain (n_bins,).

    ``10 log10(I g) + gain_db`` in dB, with [-dynamic_range_db, 0] mapped linearly onto
    [0, 255], rounded and saturated.
    """
    x = np.ascontiguousarray(np.atleast_2d(intensity), dtype=np.float32)
    out = np.empty(x.shape, dtype=np.float32)
    kernels().gain_floor(x.reshape(-1, x.shape[-1]), np.ascontiguousarray(gain_per_bin, dtype=np.float32),
                         np.float32(1e-30), out.reshape(-1, x.shape[-1]))  # max(I g, 1e-30), one pass
    x = out
    db = cv2.log(x, dst=x)  # natural log, float32
    scale = 255.0 * 10.0 / np.log(10.0) / dynamic_range_db
    offset = 255.0 * (gain_db + dynamic_range_db) / dynamic_range_db
    # saturating, rounding conversion: round(db * scale + offset) clipped to [0, 255]
    return cv2.addWeighted(db, scale, db, 0.0, offset, dtype=cv2.CV_8U)


class FanRemap:
    """Precomputed polar -> fan lookup (``cv2.remap``) for one sonar geometry.

    Args:
        fan: the fan image geometry.
        beam_azimuths_rad: (n_beams,) beam centres, evenly filling ``fan.fov_rad``.
        window_near_m, range_resolution_m, n_bins: the polar range axis.
    """

    def __init__(self, fan: FanGeometry, beam_azimuths_rad: FloatArray, window_near_m: float,
                 range_resolution_m: float, n_bins: int) -> None:
        self.fan = fan
        self.beam_azimuths_rad = np.asarray(beam_azimuths_rad, dtype=float)
        self.window_near_m = float(window_near_m)
        self.range_resolution_m = float(range_resolution_m)
        # pixel centres as a row of x and a column of y: the (height, width) grid by broadcasting
        r, a = fan.pixel_to_polar(np.arange(fan.width_px, dtype=np.float64)[None, :],
                                  np.arange(fan.height_px, dtype=np.float64)[:, None])
        n_beams = len(beam_azimuths_rad)
        spacing = (beam_azimuths_rad[-1] - beam_azimuths_rad[0]) / max(n_beams - 1, 1)
        self.beam_spacing_rad = fan.fov_rad / n_beams
        beam = (a - beam_azimuths_rad[0]) / spacing
        rbin = (r - window_near_m) / range_resolution_m - 0.5
        inside = fan.inside(r, a)
        beam = np.where(inside, np.clip(beam, 0.0, n_beams - 1), -10.0).astype(np.float32)
        rbin = np.where(inside, np.clip(rbin, 0.0, n_bins - 1), -10.0).astype(np.float32)
        self.inside = inside
        self._fixed = cv2.convertMaps(rbin, beam, cv2.CV_16SC2)
        self._nearest = cv2.convertMaps(rbin, beam, cv2.CV_16SC2, nninterpolation=True)
        self._polar_shape = (n_beams, int(n_bins))
        self._gather = _bilinear_gather(self._fixed, self._polar_shape)
        self._nearest_gather: tuple[NDArray[np.int32], NDArray[np.int32]] | None = None

    def image(self, polar: NDArray) -> NDArray:
        """Bilinear fan image (height_px, width_px) of a (n_beams, n_bins) polar image; zero
        outside the fan.

        8-bit images: the fixed-point gather of ``cv2.remap`` over the pixels inside the fan
        only (:func:`_bilinear_gather`; the same bytes); other types: ``cv2.remap``.
        """
        if polar.dtype != np.uint8 or polar.shape != self._polar_shape:
            return self._cv2_image(polar)
        dst_idx, base, frac, step = self._gather
        out = np.zeros((self.fan.height_px, self.fan.width_px), dtype=np.uint8)
        kernels().remap_bilinear_u8(np.ascontiguousarray(polar), out.reshape(-1), dst_idx, base, frac, step,
                                    _BILINEAR_WEIGHTS)
        return out

    def _cv2_image(self, polar: NDArray) -> NDArray:
        """:meth:`image` by ``cv2.remap`` (any type OpenCV remaps)."""
        return cv2.remap(polar, self._fixed[0], self._fixed[1], cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_CONSTANT, borderValue=0)

    def labels(self, polar_labels: NDArray[np.int16], fill: int) -> NDArray[np.int16]:
        """Nearest-neighbour fan image of a (n_beams, n_bins) label image; ``fill`` outside the fan.

        What ``cv2.remap`` with the nearest-neighbour maps gives, as one gather over the pixels
        inside the fan (tables built on the first call)."""
        if polar_labels.shape != self._polar_shape:
            return cv2.remap(polar_labels, self._nearest[0], None, cv2.INTER_NEAREST,
                             borderMode=cv2.BORDER_CONSTANT, borderValue=int(fill))
        if self._nearest_gather is None:
            xy = self._nearest[0]
            rows, cols = self._polar_shape
            x, y = xy[..., 0].ravel().astype(np.int32), xy[..., 1].ravel().astype(np.int32)
            dst = np.flatnonzero((x >= 0) & (x < cols) & (y >= 0) & (y < rows))
            self._nearest_gather = dst.astype(np.int32), y[dst] * cols + x[dst]
        out = np.full((self.fan.height_px, self.fan.width_px), fill, dtype=polar_labels.dtype)
        kernels().gather(np.ascontiguousarray(polar_labels), out.reshape(-1), *self._nearest_gather)
        return out

    def box_px(self, beam0: int, bin0: int, beam1: int, bin1: int) -> FloatArray:
        """Fan-image box ``[x0, y0, x1, y1]`` (px, clipped to the image) of the annular sector
        covering beams ``beam0..beam1`` and bins ``bin0..bin1`` (inclusive)."""
        half = 0.5 * self.beam_spacing_rad
        a0, a1 = self.beam_azimuths_rad[beam0] - half, self.beam_azimuths_rad[beam1] + half
        r0 = self.window_near_m + bin0 * self.range_resolution_m
        r1 = self.window_near_m + (bin1 + 1) * self.range_resolution_m
        a = np.linspace(a0, a1, 9)
        if a0 < 0.0 < a1:
            a = np.append(a, 0.0)
        r = np.array([r0, r1])
        x, y = self.fan.polar_to_pixel(r[:, None], a[None, :])
        w, h = self.fan.width_px, self.fan.height_px
        return np.array([_clamp(x.min(), 0, w - 1), _clamp(y.min(), 0, h - 1),
                         _clamp(x.max(), 0, w - 1), _clamp(y.max(), 0, h - 1)], dtype=float)


def _clamp(v: float, lo: float, hi: float) -> float:
    """``np.clip`` of one finite scalar, without its array overhead."""
    return min(max(float(v), lo), hi)


# cv2.remap's bilinear weights for 8-bit images: fractional position (i / 32, j / 32) -> the
# weights of the (top-left, top-right, bottom-left, bottom-right) neighbours, summing to 2^15
# (INTER_TAB_SIZE = 32, INTER_REMAP_COEF_BITS = 15; exact products, no rounding needed)
_I, _J = np.divmod(np.arange(32 * 32), 32)
_BILINEAR_WEIGHTS = (32 * np.stack([(32 - _I) * (32 - _J), (32 - _I) * _J, _I * (32 - _J), _I * _J],
                                   axis=1)).astype(np.int32)


def _bilinear_gather(fixed_maps: tuple[NDArray[np.int16], NDArray[np.uint16]], polar_shape: tuple[int, int]
                     ) -> tuple[NDArray[np.int32], NDArray[np.int32], NDArray[np.uint16], NDArray[np.uint8]]:
    """The fan pixels that read the polar image under ``cv2.remap``'s ``CV_16SC2`` maps: flat
    destination index, flat index of the top-left neighbour, fractional
    position (``map2``: 32 y_frac + x_frac) and which of the right / lower neighbours exist
    (bits 0 / 1; a missing one has zero weight: the maps are clipped to the image).
    Pixels whose four neighbours all fall outside the image take the border value (0)."""
    rows, cols = polar_shape
    xy, frac = fixed_maps
    x = xy[..., 0].ravel().astype(np.int32)
    y = xy[..., 1].ravel().astype(np.int32)
    idx = np.flatnonzero((x < cols) & (x >= -1) & (y < rows) & (y >= -1))
    x, y, f = x[idx], y[idx], frac.ravel()[idx]
    if np.any((x < 0) | (y < 0)):
        raise ValueError("fan maps reach left of or above the polar image")
    dx_ok, dy_ok = x + 1 < cols, y + 1 < rows
    if np.any(~dx_ok & (f % 32 != 0)) or np.any(~dy_ok & (f // 32 != 0)):
        raise ValueError("fan maps weight a neighbour outside the polar image")
    step = dx_ok.view(np.uint8) | (dy_ok.view(np.uint8) << 1)
    # in the order the polar image is read (each pixel is independent: the same bytes, fewer
    # cache misses than fan order)
    order = np.argsort(y * cols + x, kind="stable")
    return idx.astype(np.int32)[order], (y * cols + x)[order], f[order], step[order]
