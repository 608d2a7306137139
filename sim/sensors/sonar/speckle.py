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

SpeckleKind = Literal["none", "rayleigh", "k"]


def standard_exponential_f32(rng: np.random.Generator, shape: tuple[int, ...]) -> NDArray[np.float32]:
    """Exp(1) float32 samples by inversion, ``-log(1 - U)`` with ``U`` uniform float32.

    About twice as fast as ``rng.standard_exponential(dtype=np.float32)`` (one uniform draw
    and a SIMD ``cv2.log``); ``1 - U`` lies on a 2^-24 grid in (0, 1], so samples are
    finite and at most 16.6 (exceeded with probability 6e-8 by the exact law).
    """
    u = rng.random(shape, dtype=np.float32)
    np.subtract(np.float32(1.0), u, out=u)
    e = cv2.log(u, dst=u)
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
        out = np.multiply(mean, tex, out=tex)
        out += np.float32(noise_power)
    else:
        out = np.add(mean, np.float32(noise_power), dtype=np.float32)
    # echo and receiver noise are independent circular Gaussian fields: their sum is one,
    # of power (echo + noise), so one exponential draw models both
    out *= standard_exponential_f32(rng, mean.shape)
    return out
