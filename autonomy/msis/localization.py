"""Position fixes from the scanning sonar in a known pool or tank ([P002] sections 3.1-3.2).

The :class:`~autonomy.msis.sonar_buffer.SonarBuffer` holds the echo points of about one sweep
in the navigation frame. Then:

* circular pool (``circle``): MLESAC (:func:`autonomy.msis.circle_fit.mlesac_circle`) finds
  the wall circle; its centre ``c_hat`` in the navigation frame against the known centre
  ``c`` gives the navigation error, so the fix of the body origin is
  ``p_hat + (c - c_hat)``. Covariance: the centre's least-squares covariance
  ``sigma^2 (J^T J)^-1`` of the geometric circle model over the inliers (``J_i = [-u_i, -1]``,
  ``u_i`` the unit vector from the centre to point i, sigma the inliers' rms residual), plus
  a floor;
* rectangular tank (``walls``): IEPF runs on the ordered points, each run's eigenvector fit
  of at least ``min_segment_length_m`` becomes a fuzzy segment, its rho cuts widened by the
  heading uncertainty about the vehicle (``max(sqrt(cov_yaw), heading_sigma_deg)``,
  :meth:`~autonomy.msis.fuzzy_segments.FuzzySegment.with_heading_uncertainty`), and joins the
  persistent local map (:class:`autonomy.msis.fuzzy_segments.FuzzySegmentMap`, vehicle-centred,
  ``map_*`` settings): fused with the collinear map segment or added. Between fixes the map
  moves with the motion estimate of every ping (``R(rpy) v_body dt``, horizontal), growing the
  segments' uncertainty with that motion and with age and removing those too uncertain. Each
  map segment that matches a known wall (normal within ``wall_match_angle_deg``, rho within
  ``wall_match_distance_m``) is assigned to it; the segments of one wall then fuse into one
  estimate per wall (eqs. 18-19, :func:`fuse_wall_segments`), kept when its extent reaches
  ``min_wall_support_m``. Each wall estimate gives the offset of the estimate along that
  wall's normal from the vehicle's distance to the wall, which a heading error (a rotation of
  the sweep about the vehicle) leaves unchanged: with ``r`` the estimate's rho in the
  vehicle-centred frame (normal along the wall's), ``n_w . d = c_w - r - n_w . p``. With walls of both directions, the weighted least-squares
  offset ``d`` (weights ``1 / sigma^2``, sigma from the estimate's 68 % cut) makes the fix
  ``p_hat + d`` with covariance ``(H^T W H)^-1``. The walls' known directions also give the
  heading error of the estimate the sweep was placed with (``wall_heading_fix``): the mean of
  the wall estimates' signed angles from their walls' normals, weights ``1 / sigma_theta^2``
  (the fits' own angle sigmas), variance ``1 / sum(w)`` plus ``wall_heading_sigma_floor_deg``
  squared (the map's segments are not independent from fix to fix). The navigation filter
  then turns its heading by the scalar Kalman gain ``g = P_psi / (P_psi + var)`` times that
  error (``P_psi`` the estimate's heading variance), so the map is turned by ``-g`` times it
  about the vehicle to stay in the corrected heading.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from autonomy.frames import rot_from_euler, wrap_angle
from autonomy.messages import MsisPing, NavEstimate, PositionFixMsg
from autonomy.msis.circle_fit import mlesac_circle
from autonomy.msis.config import MsisLocalizationConfig
from autonomy.msis.fuzzy_segments import FuzzySegment, FuzzySegmentMap
from autonomy.msis.line_segments import fit_line, iepf_split
from autonomy.msis.sonar_buffer import SonarBuffer
from autonomy.navigation.pose_at import estimate_at

FloatArray = NDArray[np.float64]


def circle_centre_covariance(points: FloatArray, centre: FloatArray, radius_m: float) -> FloatArray:
    """(2, 2) covariance of a circle's centre fitted to (N, 2) points (module docstring)."""
    d = points - centre[None, :]
    dist = np.hypot(d[:, 0], d[:, 1])
    u = d / np.maximum(dist, 1e-9)[:, None]
    J = np.column_stack([-u, -np.ones(len(u))])
    res = dist - radius_m
    dof = max(len(points) - 3, 1)
    s2 = float(res @ res) / dof
    return s2 * np.linalg.pinv(J.T @ J)[:2, :2]


def tank_walls(centre_ne: FloatArray, size_ne: FloatArray) -> list[tuple[FloatArray, float]]:
    """Walls of an axis-aligned rectangle as (unit normal (2,), offset c) with ``n . p = c``."""
    cn, ce = centre_ne
    hn, he = 0.5 * size_ne[0], 0.5 * size_ne[1]
    return [(np.array([1.0, 0.0]), cn + hn), (np.array([-1.0, 0.0]), -(cn - hn)),
            (np.array([0.0, 1.0]), ce + he), (np.array([0.0, -1.0]), -(ce - he))]


def fuse_wall_segments(segments: list[FuzzySegment], normal: FloatArray) -> FuzzySegment:
    """One estimate of a wall from its segments of one sweep: each turned to the wall's normal
    side (``theta + pi``, ``-rho`` when its normal points away), then fused (eqs. 18-19), the
    longest first.

    Raises:
        ValueError: no segments.
    """
    if not segments:
        raise ValueError("no segments to fuse")
    n_w = np.asarray(normal, dtype=float)
    out: FuzzySegment | None = None
    for s in sorted(segments, key=lambda s: -s.length_m):
        if s.normal @ n_w < 0.0:
            s = replace(s, theta_rad=float(wrap_angle(s.theta_rad + math.pi)), rho_m=-s.rho_m)
        out = s if out is None else out.fused(s)
    return out


class MsisLocalizer:
    """Sonar buffer + feature extraction + position fix for one sonar.

    Args:
        cfg: the localisation settings.
        rng: generator for MLESAC's samples.
    """

    def __init__(self, cfg: MsisLocalizationConfig, rng: np.random.Generator) -> None:
        self.cfg = cfg
        self.rng = rng
        self.buffer = SonarBuffer(cfg.threshold_u8, cfg.min_range_m, max_age_s=2.0 * cfg.fix_interval_s, mode=cfg.echo_mode)
        self.map = FuzzySegmentMap(max_angle_rad=math.radians(cfg.map_match_angle_deg), min_match=cfg.map_min_match,
                                   motion_growth=cfg.map_motion_growth, age_growth_mps=cfg.map_age_growth_mps,
                                   max_area_m=cfg.map_max_area_m)
        self.reset()

    def reset(self) -> None:
        self.buffer.clear()
        self.map.clear()
        self._t_map_s = math.nan
        self._t_last_fix = -math.inf
        self._t_first = math.nan
        self.last_circle = None
        self.last_segments: list[FuzzySegment] = []
        self.last_walls: dict[int, FuzzySegment] = {}

    def process(self, ping: MsisPing, nav: NavEstimate) -> PositionFixMsg | None:
        """Add a ping; return a fix when one is due and found. ``nav`` (of the filter's
        time, near the ping's) is moved to the ping time first, so that the points, the map's
        motion and the fix (stamped with the ping time) all use the pose of that time."""
        if self.cfg.method == "none":
            return None
        nav = estimate_at(nav, ping.t_s)
        self.buffer.add_ping(ping, nav)
        if self.cfg.method == "walls":
            self._move_map(ping.t_s, nav)
        if math.isnan(self._t_first):
            self._t_first = ping.t_s
        if ping.t_s - max(self._t_last_fix, self._t_first) < self.cfg.fix_interval_s or \
                len(self.buffer) < self.cfg.min_points:
            return None
        pts = self.buffer.points_ne()
        fix = self._circle_fix(pts, nav) if self.cfg.method == "circle" else self._walls_fix(pts, nav)
        self._t_last_fix = ping.t_s
        self.buffer.clear()
        if fix is None:
            return None
        pos, cov, heading = fix
        cov = cov + self.cfg.fix_sigma_floor_m ** 2 * np.eye(2)
        feats: dict[str, FloatArray] = {}
        if self.cfg.method == "circle" and self.last_circle is not None:
            c = self.last_circle
            feats["circle_ne_m"] = np.array([c.centre[0], c.centre[1], c.radius_m], dtype=float)
        elif self.last_segments:
            feats["segments_ne_m"] = np.array([[s.end_a, s.end_b] for s in self.last_segments], dtype=float)
            feats["segments_rho95_m"] = np.array([s.rho0_m for s in self.last_segments], dtype=float)
        return PositionFixMsg(t_s=float(ping.t_s), pos_ne_m=pos, cov_ne_m2=cov, source=self.cfg.method,
                              points_ne_m=pts, heading_err_rad=heading[0], heading_var_rad2=heading[1], **feats)

    def _move_map(self, t_s: float, nav: NavEstimate) -> None:
        """Move the local map by the motion estimate since the last ping: ``R(rpy) v_body dt``."""
        dt = 0.0 if math.isnan(self._t_map_s) else float(t_s) - self._t_map_s
        self._t_map_s = float(t_s)
        if dt > 0.0 and self.map.segments:
            v_ned = rot_from_euler(*nav.rpy_rad) @ np.asarray(nav.vel_body_mps, dtype=float)
            self.map.move(v_ned[:2] * dt, dt)

    def _circle_fix(self, pts: FloatArray, nav: NavEstimate) -> tuple[FloatArray, FloatArray] | None:
        cfg = self.cfg
        R = cfg.pool_radius_m
        tol = cfg.radius_tolerance_m
        circle = mlesac_circle(pts, cfg.inlier_threshold_m, cfg.failure_probability, cfg.inlier_proportion, self.rng,
                               radius_range_m=(R - tol, R + tol))
        if circle is None or abs(circle.radius_m - R) > tol or circle.inliers.sum() < cfg.min_points // 2:
            return None
        self.last_circle = circle
        cov = circle_centre_covariance(pts[circle.inliers], circle.centre, circle.radius_m)
        pos = np.asarray(nav.pos_ned[:2], dtype=float) + (np.asarray(cfg.centre_ne_m) - circle.centre)
        return pos, cov, (math.nan, math.nan)

    def segments(self, pts: FloatArray, t_s: float, pivot_ne: FloatArray | None = None,
                 sigma_heading_rad: float = 0.0) -> list[FuzzySegment]:
        """Fuzzy segments of ordered points, in their frame (IEPF, eigenvector fits of at least
        ``min_segment_length_m``, heading uncertainty about the vehicle at ``pivot_ne``)."""
        cfg = self.cfg
        pivot = np.zeros(2) if pivot_ne is None else np.asarray(pivot_ne, dtype=float)
        out = []
        for a, b in iepf_split(pts, cfg.iepf_k_min, cfg.iepf_rho_max_m):
            try:
                fit = fit_line(pts[a:b])
            except ValueError:
                continue
            if fit.length_m >= cfg.min_segment_length_m:
                out.append(FuzzySegment.from_fit(fit, t_s).with_heading_uncertainty(pivot, sigma_heading_rad))
        return out

    def _walls_fix(self, pts: FloatArray, nav: NavEstimate) -> tuple[FloatArray, FloatArray, tuple[float, float]] | None:
        """Position fix (2,), its covariance (2, 2) and (heading error, its variance) (rad, rad^2;
        NaN when ``wall_heading_fix`` is off) from the walls (module docstring), or None."""
        cfg = self.cfg
        p = np.asarray(nav.pos_ned[:2], dtype=float)
        sigma_psi = max(math.sqrt(max(float(nav.cov_yaw_rad2), 0.0)), math.radians(cfg.heading_sigma_deg))
        for s in self.segments(pts, nav.t_s, p, sigma_psi):
            self.map.add(s.shifted(-p))  # into the vehicle-centred map
        self.last_segments = [s.shifted(p) for s in self.map.segments]
        walls = tank_walls(np.asarray(cfg.centre_ne_m, float), np.asarray(cfg.tank_size_ne_m, float))
        cos_max = math.cos(math.radians(cfg.wall_match_angle_deg))
        assigned: dict[int, list[FuzzySegment]] = {}
        for s in self.map.segments:
            for i, (n_w, c_w) in enumerate(walls):
                n_s, rho = s.normal, s.rho_m
                if n_s @ n_w < 0.0:  # the same line with the opposite normal
                    n_s, rho = -n_s, -rho
                if n_s @ n_w >= cos_max and abs(rho - (c_w - float(n_w @ p))) <= cfg.wall_match_distance_m:
                    assigned.setdefault(i, []).append(s)
                    break
        self.last_walls = {}
        H, z, w, ang, w_ang = [], [], [], [], []
        for i, group in sorted(assigned.items()):
            n_w, c_w = walls[i]
            est = fuse_wall_segments(group, n_w)
            if est.length_m < cfg.min_wall_support_m:
                continue
            self.last_walls[i] = est.shifted(p)  # in the navigation frame
            r = est.rho_m  # the vehicle's distance to the wall seen, along n_w
            H.append(n_w)
            z.append(c_w - r - float(n_w @ p))
            w.append(1.0 / max(est.rho1_m, 1e-3) ** 2)
            ang.append(math.atan2(n_w[0] * est.normal[1] - n_w[1] * est.normal[0], float(n_w @ est.normal)))
            w_ang.append(1.0 / max(est.sigma_theta_rad, 1e-6) ** 2)
        if len(H) < 2:
            return None
        H, z, W = np.array(H), np.array(z), np.diag(w)
        info = H.T @ W @ H
        if np.linalg.cond(info) > 1e6:
            return None  # walls of one direction only
        cov = np.linalg.inv(info)
        d = cov @ H.T @ W @ z
        heading = (math.nan, math.nan)
        if cfg.wall_heading_fix:
            heading = (float(np.average(ang, weights=w_ang)),
                       1.0 / float(np.sum(w_ang)) + math.radians(cfg.wall_heading_sigma_floor_deg) ** 2)
            p_psi = max(float(nav.cov_yaw_rad2), 0.0)
            self.map.rotate(-heading[0] * p_psi / (p_psi + heading[1]))
        return p + d, cov, heading
