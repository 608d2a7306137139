"""Detection-level side-scan ATR of paper 003 (Section V): what a tile pair reports, without
rendering.

Each object whose position in the vehicle frame lies in a tile (along-track
``[-tile_length_m, 0]``, ``tile_near_m .. tile_near_m + tile_width_m`` abeam on either side) is
detected with probability ``pd``; its reported position is the true one plus Gaussian noise
(``sigma_meas_m``, each axis); its class-1 probability ``pi`` is drawn from the Beta law of its
class (``class_beta_1`` for mine-like, ``class_beta_2`` otherwise); false alarms are Poisson with
mean ``clutter_mean`` per tile pair, uniform over the tiles, ``pi`` uniform on (0, 1).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from autonomy.mapping.spa_mapper import rotate_to_local

FloatArray = NDArray[np.float64]


class TileModel(Protocol):
    pd: float
    clutter_mean: float
    sigma_meas_m: float
    class_beta_1: tuple[float, float]
    class_beta_2: tuple[float, float]
    tile_length_m: float
    tile_width_m: float
    tile_near_m: float


class TileDetector:
    """Draws a tile pair's detections.

    Args:
        model: the detection parameters (``McmSurveyConfig`` fits).
        rng: the ATR's generator.

    Raises:
        ValueError: ``pd`` outside [0, 1] or a negative clutter mean.
    """

    def __init__(self, model: TileModel, rng: np.random.Generator) -> None:
        if not (0.0 <= model.pd <= 1.0) or model.clutter_mean < 0.0:
            raise ValueError(f"pd must be in [0, 1] and clutter_mean >= 0, got {model.pd}, {model.clutter_mean}")
        self.m = model
        self.rng = rng

    def in_tile(self, ell: FloatArray) -> NDArray[np.bool_]:
        """(...,) whether vehicle-frame positions (..., 2) lie in the tile pair."""
        m = self.m
        a = np.abs(ell[..., 1])
        return ((ell[..., 0] >= -m.tile_length_m) & (ell[..., 0] <= 0.0) & (a >= m.tile_near_m)
                & (a <= m.tile_near_m + m.tile_width_m))

    def detect(self, state: FloatArray, objects_ned: FloatArray, classes: NDArray[np.intp]
               ) -> tuple[FloatArray, FloatArray]:
        """Detections of one tile pair taken at the true vehicle ``state`` (5,).

        Args:
            state: [north, east, v_north, v_east, turn rate].
            objects_ned: (K, 2) object positions (north, east) m.
            classes: (K,) 0 mine-like, 1 other.

        Returns:
            ``(ell, pi1)``: (M, 2) positions in the vehicle frame (along, across starboard) m,
            (M,) class-1 probabilities; shuffled so order carries no information.
        """
        m, rng = self.m, self.rng
        psi = float(np.arctan2(state[3], state[2]))
        local = rotate_to_local(np.asarray(objects_ned, dtype=float) - state[:2], np.full(len(objects_ned), psi))
        seen = self.in_tile(local) & (rng.random(len(local)) < m.pd)
        ell = local[seen] + m.sigma_meas_m * rng.standard_normal((int(seen.sum()), 2))
        cls = np.asarray(classes)[seen]
        a = np.where(cls == 0, m.class_beta_1[0], m.class_beta_2[0])
        b = np.where(cls == 0, m.class_beta_1[1], m.class_beta_2[1])
        pi1 = rng.beta(a, b) if len(a) else np.zeros(0)
        n_fa = int(rng.poisson(m.clutter_mean))
        side = np.where(rng.random(n_fa) < 0.5, -1.0, 1.0)
        fa = np.column_stack([-m.tile_length_m * rng.random(n_fa),
                              side * (m.tile_near_m + m.tile_width_m * rng.random(n_fa))])
        ell = np.concatenate([ell, fa])
        pi1 = np.concatenate([pi1, rng.random(n_fa)])
        order = rng.permutation(len(pi1))
        return ell[order], pi1[order]
