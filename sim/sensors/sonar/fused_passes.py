"""Fused per-pixel passes of the echo chain and the fan resampling, compiled with numba.

Each kernel does in one pass over memory what a chain of numpy/OpenCV calls did in several,
with the same float32 / integer operations in the same order, so its output is bit for bit
that of the chain it replaces (the tests compare them on random inputs). Loaded on first use
(:func:`kernels`), so processes that render no sonar do not import numba; compiled code is
cached on disk (``cache=True``).
"""

from __future__ import annotations

from functools import cache
from types import SimpleNamespace


@cache
def kernels() -> SimpleNamespace:
    """The compiled kernels (numba imported and the cache read on the first call)."""
    import numba as nb
    import numpy as np

    f32 = np.float32
    two_m24 = f32(2.0 ** -24)

    @nb.njit(cache=True, nogil=True)
    def complement_uniform_f32(raw32, first, has_first, out):  # pragma: no cover - compiled
        """``1 - U`` for float32 uniforms ``U = (w >> 8) 2^-24`` of the uint32 words ``raw32``
        (after ``first`` when ``has_first``), as numpy's ``Generator.random(dtype=float32)``
        forms them; exact: ``1 - k 2^-24 = (2^24 - k) 2^-24``."""
        o = out.ravel()
        j = 0
        if has_first:
            o[0] = f32(16777216 - (first >> 8)) * two_m24
            j = 1
        for i in range(o.size - j):
            o[i + j] = f32(16777216 - (raw32[i] >> 8)) * two_m24

    @nb.njit(cache=True, nogil=True)
    def scale_by_neg(mean, add, log_u, out):  # pragma: no cover - compiled
        """``out = (mean + add) * -log_u`` element-wise, float32 (``-log(1 - U)`` is Exp(1))."""
        m, lu, o = mean.ravel(), log_u.ravel(), out.ravel()
        a = f32(add)
        for i in range(o.size):
            o[i] = (m[i] + a) * -lu[i]

    @nb.njit(cache=True, nogil=True)
    def gain_floor(x, gain, floor, out):  # pragma: no cover - compiled
        """``out = max(x * gain[None, :], floor)`` of a (rows, cols) float32 array."""
        rows, cols = x.shape
        lo = f32(floor)
        for r in range(rows):
            for c in range(cols):
                v = x[r, c] * gain[c]
                out[r, c] = lo if v < lo else v  # np.maximum's: NaN stays NaN

    @nb.njit(cache=True, nogil=True)
    def remap_bilinear_u8(src, dst_flat, dst_idx, base, frac, step, wtab):  # pragma: no cover - compiled
        """Fixed-point bilinear gather (``cv2.remap`` with ``CV_16SC2`` maps on 8-bit images):
        ``dst[dst_idx] = (sum_k w_k p_k + 2^14) >> 15`` over the 2 x 2 neighbours of ``base``;
        ``step`` bit 0 / bit 1: the right / lower neighbour exists (else its weight is 0)."""
        p = src.ravel()
        w = src.shape[1]
        for i in range(dst_idx.size):
            b = base[i]
            s = step[i]
            dx = 1 if s & 1 else 0
            dy = w if s & 2 else 0
            t = frac[i]
            acc = (np.int32(p[b]) * wtab[t, 0] + np.int32(p[b + dx]) * wtab[t, 1]
                   + np.int32(p[b + dy]) * wtab[t, 2] + np.int32(p[b + dy + dx]) * wtab[t, 3])
            dst_flat[dst_idx[i]] = (acc + 16384) >> 15

    return SimpleNamespace(complement_uniform_f32=complement_uniform_f32, scale_by_neg=scale_by_neg,
                           gain_floor=gain_floor, remap_bilinear_u8=remap_bilinear_u8)
