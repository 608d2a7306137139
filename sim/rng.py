"""Seeded randomness: one root seed, an independent child generator per component."""

from __future__ import annotations

import hashlib

import numpy as np


def component_rng(seed: int, component: str) -> np.random.Generator:
    """Generator for ``component`` derived from the root ``seed``.

    The stream depends only on (seed, component name), so adding or removing a
    component never changes another component's random numbers.
    """
    key = int.from_bytes(hashlib.sha256(component.encode()).digest()[:8], "little")
    return np.random.default_rng(np.random.SeedSequence([int(seed), key]))
