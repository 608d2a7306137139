"""Anchors: the symbols of the world model and their attributes (paper 000 eqs. 7-9, 17-19).

An anchor carries a symbol (``id``), the number of measurements it absorbed and two
attributes: a position from a constant-position Kalman filter (F = I, H = I) that falls back
to a fixed-uncertainty Gaussian when unmeasured for longer than a timeout, and a class pmf
over (target, not_target) updated by Bayes' rule from the ATR scores. Anchors are immutable;
an update returns a new version, so hypotheses share unchanged anchors.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from autonomy.localization.geolocate import LocalizedDetection
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
    """

    id: int
    version: int
    pos_ned: FloatArray
    cov_ned: FloatArray
    t_last_s: float
    n_detections: int
    class_pmf: FloatArray
    measurement_ids: tuple[int, ...]


def class_likelihood(score: float, cfg: WorldModelConfig) -> FloatArray:
    """Measurement pmf (2,) over CLASS_NAMES from an ATR target score (clipped)."""
    s = float(np.clip(score, cfg.class_score_floor, 1.0 - cfg.class_score_floor))
    return np.array([s, 1.0 - s])


def measurement_cov(z: LocalizedDetection, cfg: WorldModelConfig) -> FloatArray:
    """Measurement covariance (3, 3): the localisation's, or the configured fixed one."""
    if cfg.measurement_cov_m2 is not None:
        return cfg.measurement_cov_m2 * np.eye(3)
    return np.asarray(z.cov_ned, dtype=float)


def predicted_cov(anchor: Anchor, t_s: float, cfg: WorldModelConfig) -> FloatArray:
    """Position covariance (3, 3) at ``t_s``: KF prediction, or the fixed fallback."""
    dt = max(t_s - anchor.t_last_s, 0.0)
    if dt > cfg.kf_timeout_s:
        return cfg.fallback_cov_m2 * np.eye(3)
    return anchor.cov_ned + (cfg.process_noise_m2_per_s * dt) * np.eye(3)


def new_anchor(z: LocalizedDetection, uid: int, version: int, cfg: WorldModelConfig) -> Anchor:
    """Anchor initialised from its first measurement (uid becomes its symbol)."""
    return Anchor(
        id=uid,
        version=version,
        pos_ned=np.asarray(z.pos_ned, dtype=float).copy(),
        cov_ned=measurement_cov(z, cfg).copy(),
        t_last_s=float(z.t_s),
        n_detections=1,
        class_pmf=class_likelihood(z.class_score, cfg),
        measurement_ids=(uid,),
    )


def update_anchor(
    anchor: Anchor,
    z: LocalizedDetection,
    uid: int,
    t_s: float,
    version: int,
    cfg: WorldModelConfig,
) -> Anchor:
    """Kalman update of the position and Bayes update of the class pmf with ``z``."""
    P = predicted_cov(anchor, t_s, cfg)
    S = P + measurement_cov(z, cfg)
    K = np.linalg.solve(S, P).T  # P S^-1 (P, S symmetric)
    x = anchor.pos_ned + K @ (np.asarray(z.pos_ned, dtype=float) - anchor.pos_ned)
    I_K = np.eye(3) - K
    P_new = I_K @ P @ I_K.T + K @ measurement_cov(z, cfg) @ K.T  # Joseph form
    pmf = anchor.class_pmf * class_likelihood(z.class_score, cfg)
    return Anchor(
        id=anchor.id,
        version=version,
        pos_ned=x,
        cov_ned=0.5 * (P_new + P_new.T),
        t_last_s=float(t_s),
        n_detections=anchor.n_detections + 1,
        class_pmf=pmf / pmf.sum(),
        measurement_ids=anchor.measurement_ids + (uid,),
    )
