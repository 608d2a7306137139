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
  becomes a fuzzy segment, collinear segments fuse
  (:class:`autonomy.msis.fuzzy_segments.FuzzySegmentMap`); each segment that matches a known
  wall (normal within ``wall_match_angle_deg``, rho within ``wall_match_distance_m``) gives
  the offset of the estimate along that wall's normal, ``n . d = rho_true - rho_hat``. With
  walls of both directions, the weighted least-squares offset ``d`` (weights ``1 / sigma^2``,
  sigma from the segment's 68 % cut) makes the fix ``p_hat + d`` with covariance
  ``(H^T W H)^-1``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from autonomy.messages import MsisPing, NavEstimate, PositionFixMsg
from autonomy.msis.circle_fit import mlesac_circle
from autonomy.msis.config import MsisLocalizationConfig
from autonomy.msis.fuzzy_segments import FuzzySegment, FuzzySegmentMap
from autonomy.msis.line_segments import fit_line, iepf_split
from autonomy.msis.sonar_buffer import SonarBuffer

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


class MsisLocalizer:
    """Sonar buffer + feature extraction + position fix for one sonar.

    Args:
        cfg: the localisation settings.
        rng: generator for MLESAC's samples.
    """

    def __init__(self, cfg: MsisLocalizationConfig, rng: np.random.Generator) -> None:
        self.cfg = cfg
        self.rng = rng
        self.buffer = SonarBuffer(cfg.threshold_u8, cfg.min_range_m, max_age_s=2.0 * cfg.fix_interval_s)
        self.reset()

    def reset(self) -> None:
        self.buffer.clear()
        self._t_last_fix = -math.inf
        self._t_first = math.nan
        self.last_circle = None
        self.last_segments: list[FuzzySegment] = []

    def process(self, ping: MsisPing, nav: NavEstimate) -> PositionFixMsg | None:
        """Add a ping; return a fix when one is due and found."""
        if self.cfg.method == "none":
            return None
        self.buffer.add_ping(ping, nav)
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
        pos, cov = fix
        cov = cov + self.cfg.fix_sigma_floor_m ** 2 * np.eye(2)
        feats: dict[str, FloatArray] = {}
        if self.cfg.method == "circle" and self.last_circle is not None:
            c = self.last_circle
            feats["circle_ne_m"] = np.array([c.centre[0], c.centre[1], c.radius_m], dtype=float)
        elif self.last_segments:
            feats["segments_ne_m"] = np.array([[s.end_a, s.end_b] for s in self.last_segments], dtype=float)
            feats["segments_rho95_m"] = np.array([s.rho0_m for s in self.last_segments], dtype=float)
        return PositionFixMsg(t_s=float(ping.t_s), pos_ne_m=pos, cov_ne_m2=cov, source=self.cfg.method,
                              points_ne_m=pts, **feats)

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
        return pos, cov

    def segments(self, pts: FloatArray, t_s: float) -> list[FuzzySegment]:
        """Fuzzy segments of ordered points (IEPF, eigenvector fits, collinear fusion)."""
        cfg = self.cfg
        fmap = FuzzySegmentMap(max_angle_rad=math.radians(3.0), min_match=0.2)
        for a, b in iepf_split(pts, cfg.iepf_k_min, cfg.iepf_rho_max_m):
            try:
                fit = fit_line(pts[a:b])
            except ValueError:
                continue
            if fit.length_m >= cfg.min_segment_length_m:
                fmap.add(FuzzySegment.from_fit(fit, t_s))
        return fmap.segments

    def _walls_fix(self, pts: FloatArray, nav: NavEstimate) -> tuple[FloatArray, FloatArray] | None:
        cfg = self.cfg
        segs = self.segments(pts, nav.t_s)
        self.last_segments = segs
        walls = tank_walls(np.asarray(cfg.centre_ne_m, float), np.asarray(cfg.tank_size_ne_m, float))
        H, z, w = [], [], []
        cos_max = math.cos(math.radians(cfg.wall_match_angle_deg))
        for s in segs:
            for n_w, c_w in walls:
                n_s, rho = s.normal, s.rho_m
                if n_s @ n_w < 0.0:  # the same line with the opposite normal
                    n_s, rho = -n_s, -rho
                if n_s @ n_w >= cos_max and abs(rho - c_w) <= cfg.wall_match_distance_m:
                    H.append(n_w)
                    z.append(c_w - rho)
                    w.append(1.0 / max(s.rho1_m, 1e-3) ** 2)
                    break
        if len(H) < 2:
            return None
        H, z, W = np.array(H), np.array(z), np.diag(w)
        info = H.T @ W @ H
        if np.linalg.cond(info) > 1e6:
            return None  # walls of one direction only
        cov = np.linalg.inv(info)
        d = cov @ H.T @ W @ z
        return np.asarray(nav.pos_ned[:2], dtype=float) + d, cov
