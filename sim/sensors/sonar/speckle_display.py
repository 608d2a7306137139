"""Rayleigh or K speckle, receiver noise and the dB display of echo lines in one compiled pass.

The sequential path (:func:`sim.sensors.sonar.speckle.add_speckle_and_noise`, then
:func:`sim.sensors.sonar.display.to_uint8_db`) draws every pixel's uniform from the sensor's
generator, takes two logarithms per pixel and passes over the image five times. This one:

- draws **one** 64-bit key per frame from the sensor's generator; each pair of pixels hashes
  its index with the key (a counter-based generator, [Salmon2011]: two rounds of Wellons'
  ``lowbias32`` [Wellons2018], the key added before the first and xored before the second),
  and each pixel takes 16 of the 32 bits;
- with K-distributed clutter (``speckle: k``), hashes each pixel alone and takes its top 12
  bits for a unit-mean Gamma(``k_shape``) texture by a table of 4,096 quantiles (where the
  clutter mask says so), as the stream path draws ``Gamma(k) / k`` per pixel;
- turns 16 bits into a fully developed speckle factor by a table of the
  Exp(1) quantiles at ``(i + 1/2) / 65536`` scaled to unit mean (the law is exact at
  65,536 levels; the largest factor is 11.8 where inversion on float32 reaches 16.6, a
  difference in 8e-6 of the pixels);
- maps ``I tvg`` to 8 bits by a table indexed by the float's exponent and top
  :data:`LUT_MANTISSA_BITS` mantissa bits (the display law at each bucket's middle: the dB
  value is within 0.004 dB of the exact one; a pixel whose exact grey level lies that close to
  a rounding boundary may land one level off).

Same seed, same frames on one machine; across machines the integer hash is exact and the
floating-point parts are one multiply-add per pixel. The frames are not those of the
sequential path (other draws); their statistics are.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import NDArray
from scipy.special import gammaincinv

from sim.sensors.sonar.fused_passes import kernels

EXP_TABLE_BITS = 16  # speckle factor levels: 2^16 quantiles of Exp(1)
TEXTURE_TABLE_BITS = 12  # K texture levels: 2^12 quantiles of Gamma(k) / k
LUT_MANTISSA_BITS = 9  # mantissa bits of the display table's index (bucket width 2^-9 relative: 0.008 dB)
_SHIFT = 23 - LUT_MANTISSA_BITS


def _unit_mean_table(quantile_fn, bits: int) -> NDArray[np.float32]:
    """(2**bits,) float32 ``quantile_fn(q)`` at the bin middles ``q = (i + 1/2) / 2**bits``,
    scaled to unit mean; read-only (a cached table is shared)."""
    q = (np.arange(1 << bits, dtype=np.float64) + 0.5) / (1 << bits)
    v = quantile_fn(q)
    table = (v / v.mean()).astype(np.float32)
    table.flags.writeable = False
    return table


@lru_cache(maxsize=4)
def exponential_quantiles(bits: int = EXP_TABLE_BITS) -> NDArray[np.float32]:
    """(2**bits,) float32 quantiles of Exp(1) at ``(i + 1/2) / 2**bits``, scaled to unit mean
    (built once per process, read-only)."""
    return _unit_mean_table(lambda q: -np.log1p(-q), bits)


def gamma_texture_quantiles(k_shape: float, bits: int = TEXTURE_TABLE_BITS) -> NDArray[np.float32]:
    """(2**bits,) float32 quantiles of Gamma(``k_shape``) at ``(i + 1/2) / 2**bits``, scaled to
    unit mean: the K distribution's texture (its variance 1 / ``k_shape``, less the cut tail)."""
    return _unit_mean_table(lambda q: gammaincinv(float(k_shape), q), bits)


def db_display_table(gain_db: float, dynamic_range_db: float) -> NDArray[np.uint8]:
    """The dB display law of :func:`sim.sensors.sonar.display.to_uint8_db` tabulated on
    positive float32 bit patterns ``>> (23 - LUT_MANTISSA_BITS)``: (2**(8 + LUT_MANTISSA_BITS),) uint8.

    Entry ``i`` is ``round(255 (10 log10(x) + gain_db + DR) / DR)`` saturated to [0, 255], at
    the bucket's middle ``x`` (values below 1e-30 as 1e-30, as the exact law; infinities 255)."""
    n = 1 << (8 + LUT_MANTISSA_BITS)
    bits = (np.arange(n, dtype=np.uint64) << np.uint64(_SHIFT)) | np.uint64(1 << (_SHIFT - 1))
    with np.errstate(over="ignore", invalid="ignore"):
        x = bits.astype(np.uint32).view(np.float32).astype(np.float64)
        db = 10.0 * np.log10(np.maximum(x, 1e-30))
        grey = np.rint(255.0 * (db + gain_db + dynamic_range_db) / dynamic_range_db)
    grey = np.where(np.isnan(grey), 255.0, grey)  # exponent 255: inf and NaN patterns
    return np.clip(grey, 0.0, 255.0).astype(np.uint8)


class CounterSpeckleDisplay:
    """Tables for :meth:`realise_display`, built once per echo chain.

    Args:
        tvg_gain: (n_bins,) float32 time-varied gain per range bin (linear power).
        gain_db, dynamic_range_db: the display's gain and span (dB), as
            :func:`sim.sensors.sonar.display.to_uint8_db`.
        noise_power: receiver noise power added to the mean before the speckle (linear).
        k_shape: the K distribution's shape (``speckle: k``); None: Rayleigh speckle.
    """

    def __init__(self, tvg_gain: NDArray[np.float32], gain_db: float, dynamic_range_db: float,
                 noise_power: float, k_shape: float | None = None) -> None:
        self.tvg_gain = np.ascontiguousarray(tvg_gain, dtype=np.float32)
        self.noise_power = np.float32(noise_power)
        self.exp_table = exponential_quantiles()
        self.texture_table = None if k_shape is None else gamma_texture_quantiles(k_shape)
        self.lut = db_display_table(gain_db, dynamic_range_db)

    def realise_display(self, mean: NDArray[np.float32], rng: np.random.Generator,
                        clutter: NDArray[np.bool_] | None = None) -> tuple[NDArray[np.float32], NDArray[np.uint8]]:
        """One frame's (n_lines, n_bins) received intensity ``(mean T + noise) E`` (linear
        power; ``T`` the K texture where ``clutter``, default everywhere, 1 elsewhere and with
        Rayleigh speckle) and its 8-bit display, from one 64-bit draw of ``rng``.

        Raises:
            ValueError: ``mean`` is not 2-D with ``n_bins`` columns, or ``clutter`` is not its shape.
        """
        if mean.ndim != 2 or mean.shape[1] != self.tvg_gain.size:
            raise ValueError(f"mean must be (n_lines, {self.tvg_gain.size}), got {mean.shape}")
        key = int(rng.integers(0, 1 << 64, dtype=np.uint64))
        rows, cols = mean.shape
        intensity = np.empty((rows, cols), dtype=np.float32)
        out = np.empty((rows, cols), dtype=np.uint8)
        m = np.ascontiguousarray(mean, dtype=np.float32)
        k0, k1 = np.uint32(key & 0xFFFFFFFF), np.uint32(key >> 32)
        if self.texture_table is not None:
            if clutter is None:
                mask = np.ones((rows, cols), dtype=np.uint8)
            elif clutter.shape != mean.shape:
                raise ValueError(f"clutter must have the mean's shape {mean.shape}, got {clutter.shape}")
            else:
                mask = np.ascontiguousarray(clutter).view(np.uint8)
            kernels().counter_k_speckle_display(m, mask, self.noise_power, self.tvg_gain, k0, k1, self.exp_table,
                                                self.texture_table, self.lut, np.uint32(_SHIFT), intensity, out)
            return intensity, out
        hashes = np.empty((cols + 1) // 2, dtype=np.uint32)
        kernels().counter_speckle_display(m, self.noise_power, self.tvg_gain, k0, k1, self.exp_table, self.lut,
                                          np.uint32(_SHIFT), hashes, intensity, out)
        return intensity, out
