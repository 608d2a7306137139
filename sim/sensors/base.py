"""What every hull-mounted sensor holds: its config, rate, latency, mount and noise stream."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike


class HullSensor:
    """Base of the sensors fixed on the hull.

    Args:
        cfg: the sensor's config block (provides ``rate_hz`` and ``latency_s``).
        mount_pos_body_m: (3,) FRD offset of the sensor from the body origin, m.
        rng: the sensor's own generator (``sim.rng.component_rng(seed, name)``).
    """

    name = "sensor"

    def __init__(self, cfg: Any, mount_pos_body_m: ArrayLike, rng: np.random.Generator) -> None:
        self.cfg = cfg
        self.rate_hz = cfg.rate_hz
        self.latency_s = cfg.latency_s
        self.mount_pos_body_m = np.asarray(mount_pos_body_m, dtype=float).reshape(3)
        self._rng = rng
