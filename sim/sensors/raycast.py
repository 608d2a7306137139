"""Ray casting behind a small interface.

Sensors that cast rays (FLS, DVL beams, altimeter, later MSIS) take a :class:`RayCaster`.
:class:`MujocoRayCaster` wraps ``mujoco.mj_multiRay`` on the compiled scene; tests use
the analytic casters in :mod:`sim.sensors.analytic_caster`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
BACKGROUND_ID = -1  # object id of seabed, walls and anything not a scene object


@dataclass(frozen=True, slots=True)
class RayHits:
    """Result of casting N rays.

    Attributes:
        dist_m: (N,) distance to the first hit, ``inf`` where nothing was hit in range.
        normal_ned: (N, 3) unit surface normal at the hit (zeros where no hit).
        reflectivity: (N,) acoustic reflectivity of the surface hit, in [0, 1] (0 if none).
        object_id: (N,) scene-object id hit, :data:`BACKGROUND_ID` for seabed/walls,
            and -2 where nothing was hit.
    """

    dist_m: FloatArray
    normal_ned: FloatArray
    reflectivity: FloatArray
    object_id: NDArray[np.int64]


class RayCaster(Protocol):
    """Anything that can cast rays from one origin into the scene."""

    def cast(self, origin_ned: FloatArray, dirs_ned: FloatArray, max_range_m: float) -> RayHits:
        """Cast rays from ``origin_ned`` (3,) along unit ``dirs_ned`` (N, 3)."""
        ...
