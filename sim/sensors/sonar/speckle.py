"""Speckle and receiver noise on echo intensities (pure numpy + OpenCV).

Fully developed speckle: the echo's complex amplitude is circular Gaussian, so its intensity
is exponential about its mean (Rayleigh amplitude). Heavy-tailed seabed clutter: the mean is
first modulated by a unit-mean Gamma texture, which gives K-distributed intensity
(Abraham and Lyons; see ``docs/references.md``).
"""

from __future__ import annotations

from typing import Literal

import cv2
import numpy as np
from numpy.typing import NDArray

from sim.sensors.sonar.fused_passes import kernels

SpeckleKind = Literal["none", "rayleigh", "k"]


PCG64_MULTIPLIER = 0x2360ED051FC65DA44385DF649FCCF645  # numpy's PCG64 (PCG's default 128-bit LCG multiplier)
MASK128 = (1 << 128) - 1


def _hi_lo(x: int) -> tuple[int, int]:
    return x >> 64, x & 0xFFFFFFFFFFFFFFFF


def _lcg_jump(inc: int, steps: int) -> tuple[int, int]:
    """``(M^steps, (M^(steps-1) + ... + M + 1) inc)`` mod 2^128: ``steps`` LCG steps as one."""
    a, c = 1, 0
    for _ in range(steps):
        a, c = (a * PCG64_MULTIPLIER) & MASK128, (c * PCG64_MULTIPLIER + inc) & MASK128
    return a, c


def complement_uniform_f32(rng: np.random.Generator, shape: tuple[int, ...]) -> NDArray[np.float32]:
    """``1 - U`` (float32, in (0, 1] on a 2^-24 grid) for ``U = rng.random(shape, dtype=np.float32)``.

    Bit for bit those values, and the generator is left in the state that call leaves it in.
    For numpy's PCG64 the uint32 words (low half of each uint64 first, a spare half buffered
    as numpy does) come from the 128-bit LCG state stepped inside one compiled pass
    (:mod:`sim.sensors.sonar.fused_passes`; PCG64's LCG step and XSL-RR output, [ONeill2014]
    in ``docs/references.md``), four states side by side; any other bit generator takes
    ``rng.random``.
    """
    n = int(np.prod(shape, dtype=np.int64))
    bg = rng.bit_generator
    if type(bg) is not np.random.PCG64 or n == 0:
        u = rng.random(shape, dtype=np.float32)
        return np.subtract(np.float32(1.0), u, out=u)
    state = bg.state
    has_first, first = int(state["has_uint32"]), int(state["uinteger"])
    out = np.empty(shape, dtype=np.float32)
    need = n - has_first  # words still to draw
    if need == 0:
        out.ravel()[0] = np.float32(16777216 - (first >> 8)) * np.float32(2.0 ** -24)
        state["has_uint32"] = 0
        bg.state = state
        return out
    s, inc = int(state["state"]["state"]), int(state["state"]["inc"])
    jump_m, jump_c = _lcg_jump(inc, 4)
    u64 = np.uint64
    last_hi, last_lo, spare = kernels().pcg64_complement_uniform_f32(
        *(u64(v) for v in (*_hi_lo(s), *_hi_lo(PCG64_MULTIPLIER), *_hi_lo(inc))),
        tuple(u64(v) for v in _hi_lo(jump_m)), tuple(u64(v) for v in _hi_lo(jump_c)),
        u64(first), bool(has_first), out)
    state["state"]["state"] = (int(last_hi) << 64) | int(last_lo)
    state["has_uint32"] = need % 2
    state["uinteger"] = int(spare)  # numpy leaves the last high half there even when used
    bg.state = state
    return out


def standard_exponential_f32(rng: np.random.Generator, shape: tuple[int, ...]) -> NDArray[np.float32]:
    """Exp(1) float32 samples by inversion, ``-log(1 - U)`` with ``U`` uniform float32.

    About twice as fast as ``rng.standard_exponential(dtype=np.float32)`` (one uniform draw,
    :func:`complement_uniform_f32`, and a SIMD ``cv2.log``); ``1 - U`` lies on a 2^-24 grid
    in (0, 1], so samples are finite and at most 16.6 (exceeded with probability 6e-8 by the
    exact law).
    """
    u = complement_uniform_f32(rng, shape)
    e = cv2.log(u, dst=u)  # in place
    np.negative(e, out=e)
    return e


def add_speckle_and_noise(mean: NDArray[np.float32], rng: np.random.Generator, kind: SpeckleKind,
                          noise_power: float, *, k_shape: float = 2.0,
                          clutter: NDArray[np.bool_] | None = None) -> NDArray[np.float32]:
    """One noisy realisation of a mean-intensity array (any shape, float32, linear power).

    ``rayleigh``: intensity = (mean + noise_power) * Exp(1) (fully developed speckle on the
    echo plus receiver noise). ``k``: where ``clutter`` (default everywhere) the echo mean is
    first scaled by a unit-mean Gamma(k_shape) texture, giving K-distributed clutter.
    ``none``: mean plus exponential receiver noise only.

    Returns:
        A new float32 array shaped like ``mean``.
    """
    if kind == "none":
        out = mean.copy()
        if noise_power > 0.0:
            out += np.float32(noise_power) * standard_exponential_f32(rng, mean.shape)
        return out
    if kind == "k":
        tex = rng.standard_gamma(k_shape, mean.shape, dtype=np.float32)
        tex *= np.float32(1.0 / k_shape)
        if clutter is not None:
            np.copyto(tex, np.float32(1.0), where=~clutter)
        mean = np.multiply(mean, tex, out=tex)
    # echo and receiver noise are independent circular Gaussian fields: their sum is one,
    # of power (echo + noise), so one exponential draw models both:
    # (mean + noise) * -log(1 - U), in one pass
    u = complement_uniform_f32(rng, mean.shape)
    log_u = cv2.log(u, dst=u)  # in place
    kernels().scale_by_neg(np.ascontiguousarray(mean, dtype=np.float32), np.float32(noise_power), log_u, log_u)
    return log_u
