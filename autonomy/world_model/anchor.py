"""Anchors: the symbols of the world model and their attributes (paper 000 eqs. 7-9, 17-19).

An anchor carries a symbol (``id``), the number of measurements it absorbed and two
attributes: a position, a Gaussian kept by the estimation roles the world model is built
from (constant-position Kalman filter falling back to a fixed-uncertainty Gaussian when
unmeasured for longer than a timeout), and a class pmf over (target, not_target) updated by
Bayes' rule from the ATR scores. Anchors are immutable; an update returns a new version,
so hypotheses share unchanged anchors.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from autonomy.localization.geolocate import SHARED_ERRORS, LocalizedDetection
from autonomy.world_model.config import WorldModelConfig

FloatArray = NDArray[np.float64]
CLASS_NAMES = ("target", "not_target")


@dataclass(frozen=True, slots=True)
class Anchor:
    """One version of an anchored object.

    Attributes:
        id: symbol, the uid of the measurement that created the anchor.
        version: unique id of this version (identical histories share one version).
        pos_ned: (3,) filtered position, m.
        cov_ned: (3, 3) filtered covariance at ``t_last_s``, m^2.
        t_last_s: time of the last measurement.
        n_detections: measurements absorbed.
        class_pmf: (2,) probabilities of CLASS_NAMES.
        measurement_ids: uids of the absorbed measurements, oldest first.
        consider_ned: (3, q) sensitivity of the position error to the consider parameters
            of :data:`autonomy.localization.geolocate.SHARED_ERRORS` (``cov_ned`` includes
            ``consider_ned @ consider_ned.T``), or None (no shared error).
    """

    id: int
    version: int
    pos_ned: FloatArray
    cov_ned: FloatArray
    t_last_s: float
    n_detections: int
    class_pmf: FloatArray
    measurement_ids: tuple[int, ...]
    consider_ned: FloatArray | None = None


def class_likelihood(score: float, cfg: WorldModelConfig) -> FloatArray:
    """Measurement pmf (2,) over CLASS_NAMES from an ATR target score (clipped)."""
    floor = cfg.class_score_floor
    s = min(max(float(score), floor), 1.0 - floor)  # np.clip's result, without its per-call overhead
    return np.array([s, 1.0 - s])


def class_update(pmf: FloatArray, likelihood: FloatArray) -> FloatArray:
    """Bayes' rule on the class pmf (2,) with a measurement likelihood (2,)."""
    post = pmf * likelihood
    return post / post.sum()


def class_update_batch(pmf: FloatArray, likelihood: FloatArray) -> FloatArray:
    """:func:`class_update` of N pairs at once: pmfs (N, 2) and likelihoods (N, 2) -> (N, 2),
    row i bit for bit ``class_update(pmf[i], likelihood[i])``."""
    post = pmf * likelihood
    return post / post.sum(axis=-1, keepdims=True)


def measurement_cov(z: LocalizedDetection, cfg: WorldModelConfig) -> FloatArray:
    """Measurement covariance (3, 3): the localisation's, or the configured fixed one."""
    if cfg.measurement_cov_m2 is not None:
        return cfg.measurement_cov_m2 * np.eye(3)
    return np.asarray(z.cov_ned, dtype=float)


def measurement_shared(z: LocalizedDetection) -> FloatArray:
    """The measurement's shared-error sensitivity (3, q = len(SHARED_ERRORS)): its
    ``shared_ned``, or zeros when it has none. (Whether shared errors are considered at all
    is the world model's choice: :class:`autonomy.world_model.PMHA` calls this only when
    ``consider_shared_errors`` is on and no fixed covariance replaces the localisation's.)

    Raises:
        ValueError: ``shared_ned`` of another shape.
    """
    q = len(SHARED_ERRORS)
    if z.shared_ned is None:
        return np.zeros((3, q))
    L = np.asarray(z.shared_ned, dtype=float)
    if L.shape != (3, q):
        raise ValueError(f"LocalizedDetection.shared_ned must have shape (3, {q}), got {L.shape}")
    return L
