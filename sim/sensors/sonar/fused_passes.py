"""Fused per-pixel passes of the echo chain and the fan resampling, compiled with numba.

Each kernel does in one pass over memory what a chain of numpy/OpenCV calls did in several,
with the same float32 / integer operations in the same order, so its output is bit for bit
that of the chain it replaces (the tests compare them on random inputs). Loaded on first use
(:func:`kernels`), so processes that render no sonar do not import numba; compiled code is
cached on disk (``cache=True``).
"""

from __future__ import annotations

from types import ModuleType


def kernels() -> ModuleType:
    """The compiled kernels (:mod:`sim.sensors.sonar.compiled_kernels`; numba is imported and
    the on-disk cache read on the first call)."""
    from sim.sensors.sonar import compiled_kernels

    return compiled_kernels
