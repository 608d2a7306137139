"""Geolocalise ATR detections: (range, azimuth) -> NED position with a 3x3 covariance.

Chain (paper 000 section IV): sonar frame by eq. 4 (planar) or eqs. 5-6 (flat seabed with
the altitude), -> body with the sonar mount extrinsics, -> NED with the navigation estimate
(never ground truth). The covariance is the first-order propagation of range, azimuth,
box extent, altitude, attitude and mount-tilt noise (numerical Jacobian) plus the
navigation position covariance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.frames import rot_from_euler
from autonomy.localization.config import LocalizationConfig
from autonomy.localization.sonar_projection import (
    flat_seabed_point_sonar,
    planar_point_sonar,
    sonar_to_body_rotation,
)
from autonomy.messages import Detection, NavEstimate
from autonomy.sonar_frame import mount_euler_zyx, spherical_to_sonar
from autonomy.sonar_geometry import FanGeometry

FloatArray = NDArray[np.float64]

# Perturbed inputs, in this order: range, azimuth, altitude, roll, pitch, yaw, mount tilt.
_STEPS = np.array([1e-4, 1e-6, 1e-4, 1e-6, 1e-6, 1e-6, 1e-6])
_STEP_DIAG = np.diag(_STEPS)
_TWO_STEPS = (2.0 * _STEPS)[:, None]


@dataclass(frozen=True, slots=True)
class LocalizedDetection:
    """A detection placed in NED, the PMHA measurement.

    Attributes:
        t_s: frame time, s.
        pos_ned: (3,) position, m.
        cov_ned: (3, 3) covariance, m^2.
        class_score: ATR probability that it is a target, in [0, 1].
        class_name: ATR class label.
        method: "flat_seabed" or "planar" (planar also when no altitude was available).
        shared_ned: (3, q) m, or None (no shared part): the error this detection shares with
            others, as columns on unit-variance consider parameters (:data:`SHARED_ERRORS`:
            the navigation position and heading errors, common to every detection taken from
            one drifting pose, and where on the object the box lands, common to the looks at
            one object). ``cov_ned`` includes ``shared_ned @ shared_ned.T``; the world model
            keeps these parts from averaging out over repeated looks ([Schmidt1966] in
            docs/references.md).
    """

    t_s: float
    pos_ned: FloatArray
    cov_ned: FloatArray
    class_score: float
    class_name: str = "target"
    method: str = "flat_seabed"
    shared_ned: FloatArray | None = None


#: The consider parameters of :attr:`LocalizedDetection.shared_ned`'s columns, in order.
SHARED_ERRORS = ("nav_north", "nav_east", "nav_down", "nav_heading", "point_north", "point_east", "point_down")


def covariance_root(cov: ArrayLike) -> FloatArray:
    """A (3, 3) factor ``L`` with ``L @ L.T == cov`` for a symmetric positive semi-definite
    ``cov`` (eigen-decomposition, so a singular covariance, e.g. a known pose, gives zeros)."""
    c = np.asarray(cov, dtype=float)
    w, v = np.linalg.eigh(0.5 * (c + c.T))
    return v * np.sqrt(np.clip(w, 0.0, None))


def sonar_point_ned(
    range_m: float,
    azimuth_rad: float,
    pos_ned: ArrayLike,
    rpy_rad: ArrayLike,
    mount_pos_body_m: ArrayLike,
    mount_rpy_rad: ArrayLike,
    *,
    altitude_m: float | None,
) -> FloatArray:
    """NED point (3,) of a sonar return; ``altitude_m`` None -> eq. 4, else eqs. 5-6.

    ``altitude_m`` is the body origin's height above the seabed (altimeter/DVL).
    """
    R_nb = rot_from_euler(*np.asarray(rpy_rad, dtype=float))
    R_bs = sonar_to_body_rotation(mount_rpy_rad)
    mount = np.asarray(mount_pos_body_m, dtype=float)
    lever_ned = R_nb @ mount
    if altitude_m is None:
        p_s = planar_point_sonar(range_m, azimuth_rad)
    else:
        sonar_altitude_m = altitude_m - lever_ned[2]
        p_s = flat_seabed_point_sonar(range_m, azimuth_rad, sonar_altitude_m, R_nb @ R_bs)
    return np.asarray(pos_ned, dtype=float) + lever_ned + R_nb @ (R_bs @ p_s)


def _rotations_zyx(rpy: FloatArray) -> FloatArray:
    """Batched ``Rz(yaw) Ry(pitch) Rx(roll)`` for rows (K, 3) -> (K, 3, 3)."""
    cr, sr = np.cos(rpy[:, 0]), np.sin(rpy[:, 0])
    cp, sp = np.cos(rpy[:, 1]), np.sin(rpy[:, 1])
    cy, sy = np.cos(rpy[:, 2]), np.sin(rpy[:, 2])
    R = np.empty((rpy.shape[0], 3, 3))
    R[:, 0, 0] = cy * cp
    R[:, 0, 1] = cy * sp * sr - sy * cr
    R[:, 0, 2] = cy * sp * cr + sy * sr
    R[:, 1, 0] = sy * cp
    R[:, 1, 1] = sy * sp * sr + cy * cr
    R[:, 1, 2] = sy * sp * cr - cy * sr
    R[:, 2, 0] = -sp
    R[:, 2, 1] = cp * sr
    R[:, 2, 2] = cp * cr
    return R


def relative_points_ned(
    x: FloatArray, mount_pos_body_m: ArrayLike, mount_roll_rad: float, mount_yaw_rad: float, use_seabed: bool
) -> FloatArray:
    """Batched :func:`sonar_point_ned` relative to the body origin.

    Rows of ``x`` (K, 7): range, azimuth, altitude (ignored unless ``use_seabed``), roll,
    pitch, yaw, mount tilt. Returns (K, 3) NED offsets from the vehicle position.
    """
    x = np.asarray(x, dtype=float)
    r, a = x[:, 0], x[:, 1]
    R_nb = _rotations_zyx(x[:, 3:6])
    k = len(x)
    mount = np.empty((k, 3))
    mount[:, 0] = mount_roll_rad
    mount[:, 1] = x[:, 6]
    mount[:, 2] = mount_yaw_rad
    R_bs = _rotations_zyx(mount_euler_zyx(mount))
    R_ns = R_nb @ R_bs
    lever = R_nb @ np.asarray(mount_pos_body_m, dtype=float)
    if use_seabed:
        sonar_alt = x[:, 2] - lever[:, 2]
        A = R_ns[:, 2, 0] * np.cos(a) + R_ns[:, 2, 1] * np.sin(a)
        B = R_ns[:, 2, 2]
        phi = np.arcsin(np.clip(sonar_alt / (r * np.hypot(A, B)), -1.0, 1.0)) - np.arctan2(A, B)
    else:
        phi = np.zeros(k)
    p_s = spherical_to_sonar(r, a, phi)
    return lever + np.einsum("kij,kj->ki", R_ns, p_s)


def box_polar_extent(box_xyxy_px: ArrayLike, geometry: FanGeometry) -> tuple[float, float]:
    """(range extent m, azimuth extent rad) spanned by a fan-image box's corners."""
    x0, y0, x1, y1 = np.asarray(box_xyxy_px, dtype=float)
    r, a = geometry.pixel_to_polar(np.array([x0, x1, x0, x1]), np.array([y0, y0, y1, y1]))
    return float(np.ptp(r)), float(np.ptp(a))


def localize(
    detection: Detection,
    nav: NavEstimate,
    mount_pos_body_m: ArrayLike,
    mount_rpy_rad: ArrayLike,
    cfg: LocalizationConfig,
    *,
    geometry: FanGeometry | None = None,
) -> LocalizedDetection:
    """Geolocalise one detection with the navigation estimate ``nav``.

    ``geometry`` (the frame's fan geometry) lets the box extent enter the covariance.
    The flat-seabed method falls back to eq. 4 when ``nav.altitude_m`` is not finite.
    """
    range_m = float(detection.range_m) + cfg.range_offset_m
    use_seabed = cfg.method == "flat_seabed" and np.isfinite(nav.altitude_m)
    mount_rpy = np.asarray(mount_rpy_rad, dtype=float)
    x0 = np.array(
        [range_m, detection.azimuth_rad, nav.altitude_m if use_seabed else 0.0,
         *np.asarray(nav.rpy_rad, dtype=float), mount_rpy[1]]
    )

    # x0 and its central-difference perturbations, evaluated in one batch
    pts = relative_points_ned(np.vstack([x0, x0 + _STEP_DIAG, x0 - _STEP_DIAG]), mount_pos_body_m, mount_rpy[0],
                              mount_rpy[2], use_seabed)
    p_rel = pts[0]
    n_in = x0.size
    J = ((pts[1:1 + n_in] - pts[1 + n_in:]) / _TWO_STEPS).T

    var_r = cfg.range_sigma_m**2
    var_a = cfg.azimuth_sigma_rad**2
    if geometry is not None and cfg.box_sigma_fraction > 0.0:
        dr, da = box_polar_extent(detection.box_xyxy_px, geometry)
        var_r += (cfg.box_sigma_fraction * dr) ** 2
        var_a += (cfg.box_sigma_fraction * da) ** 2
    var_att = cfg.attitude_sigma_rad**2
    # per-frame errors; the heading error is a shared one (below)
    var_in = np.array(
        [var_r, var_a, cfg.altitude_sigma_m**2 if use_seabed else 0.0, var_att, var_att,
         0.0, cfg.tilt_sigma_rad**2]
    )
    shared = np.empty((3, len(SHARED_ERRORS)))
    shared[:, :3] = covariance_root(nav.cov_pos_ned)
    shared[:, 3] = J[:, 5] * np.sqrt(max(float(nav.cov_yaw_rad2), 0.0))
    shared[:, 4:] = cfg.min_sigma_m * np.eye(3)
    cov = (J * var_in) @ J.T + shared @ shared.T
    cov = 0.5 * (cov + cov.T)
    return LocalizedDetection(
        t_s=float(detection.t_s),
        pos_ned=np.asarray(nav.pos_ned, dtype=float) + p_rel,
        cov_ned=cov,
        class_score=float(detection.score),
        class_name=detection.class_name,
        method="flat_seabed" if use_seabed else "planar",
        shared_ned=shared,
    )
