"""Fuzzy segments ([P002] section 3.2.2, eqs. 12-19): a line segment with a trapezoidal fuzzy
set on its ``rho``.

* Trapezoid ``(-rho0, -rho1, rho1, rho0)`` about the segment's rho: the 68 % interval
  (``t_{k-1; 0.84} sigma_rho``) is the cut at membership 1, the 95 % interval
  (``t_{k-1; 0.975} sigma_rho``) the cut at membership 0 (eq. 14).
* Bounded sum of independent uncertainty sources (eq. 12): cuts add (motion and age grow a
  segment's uncertainty, :meth:`FuzzySegment.grown`).
* Matching degree of two trapezoids (eq. 17) as we read it: ``A_xy / min(A_x, A_y)``, the
  area of their intersection over the smaller area (1 when one lies inside the other).
* Collinear segments (eq. 16: normals within ``max_angle`` and matching degree at least
  ``min_match``) fuse (eqs. 18-19): theta by inverse-variance weights of the fits' sigma_theta,
  rho by inverse-variance weights of the 95 % cuts, each segment's rho first carried to the
  fused normal through its mid point (``rho_i + (n_r - n_i) . m_i``, so pieces of one wall at
  slightly different angles agree where they were seen), cuts combined as independent
  estimates ``(c_a^-2 + c_b^-2)^-1/2``, end points the extreme projections of the four ends onto
  the fused line.
* Heading uncertainty (:meth:`FuzzySegment.with_heading_uncertainty`): the points of a sweep
  are placed with the estimated heading, so a heading error ``d_psi`` rotates the segment about
  the vehicle position ``p``: its normal turns by ``d_psi`` and its points move along the
  normal by ``d_psi`` times their distance from ``p`` along the segment. ``sigma_psi`` is kept
  apart from the fit's ``sigma_theta`` (it is common to every segment of one sweep, so it does
  not average out in a fusion; :attr:`FuzzySegment.sigma_theta_total_rad` adds both) and widens
  the rho cuts by ``z sigma_psi L`` (``L`` the farthest end's distance from ``p`` along the
  segment, ``z`` = 1 and 1.96 for the 68 % and 95 % cuts), bounded sum (eq. 12).
* The local map (:class:`FuzzySegmentMap`) keeps the segments from sweep to sweep in a
  vehicle-centred frame: moved with the vehicle's motion estimate, grown with that motion and
  with age (bounded sum, eq. 12), fused with new collinear segments (eqs. 16-19), and dropped
  once their trapezoid area ``rho0 + rho1`` exceeds a threshold.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from autonomy.frames import wrap_angle
from autonomy.msis.line_segments import LineFit, t_quantile

FloatArray = NDArray[np.float64]
CUT_MU1 = 0.68  #: confidence of the membership-1 cut
CUT_MU0 = 0.95  #: confidence of the membership-0 cut


def trapezoid_membership(x: FloatArray, centre: float, rho1: float, rho0: float) -> FloatArray:
    """Membership of ``x`` in the trapezoid ``centre + (-rho0, -rho1, rho1, rho0)``."""
    d = np.abs(np.asarray(x, dtype=float) - centre)
    if rho0 <= rho1:
        return (d <= rho1).astype(float)
    return np.clip((rho0 - d) / (rho0 - rho1), 0.0, 1.0)


def matching_degree(c_a: float, rho1_a: float, rho0_a: float, c_b: float, rho1_b: float, rho0_b: float,
                    n_grid: int = 4001) -> float:
    """``A_xy / min(A_x, A_y)`` of two trapezoids (module docstring), by the trapezoidal rule on
    ``n_grid`` points over their joint support. In [0, 1]."""
    lo = min(c_a - rho0_a, c_b - rho0_b)
    hi = max(c_a + rho0_a, c_b + rho0_b)
    if not hi > lo:
        return 1.0
    x = np.linspace(lo, hi, n_grid)
    ma = trapezoid_membership(x, c_a, rho1_a, rho0_a)
    mb = trapezoid_membership(x, c_b, rho1_b, rho0_b)
    area_ab = float(np.trapezoid(np.minimum(ma, mb), x))
    small = min(rho0_a + rho1_a, rho0_b + rho1_b)
    return min(area_ab / small, 1.0) if small > 0 else 0.0


@dataclass(frozen=True, slots=True)
class FuzzySegment:
    """A segment with its trapezoidal rho uncertainty.

    Attributes:
        theta_rad, rho_m: the line ``x cos(theta) + y sin(theta) = rho`` (its frame's metres).
        sigma_theta_rad: theta's standard deviation.
        rho1_m, rho0_m: half widths of the membership-1 and -0 cuts, m.
        end_a, end_b: (2,) end points, m.
        t_s: time of the latest observation fused in.
        sigma_heading_rad: heading standard deviation of the estimate the points were placed
            with (common to the segments of one sweep; module docstring).
    """

    theta_rad: float
    rho_m: float
    sigma_theta_rad: float
    rho1_m: float
    rho0_m: float
    end_a: FloatArray
    end_b: FloatArray
    t_s: float
    sigma_heading_rad: float = 0.0

    @classmethod
    def from_fit(cls, fit: LineFit, t_s: float) -> "FuzzySegment":
        """eq. 14: the 68 % and 95 % Student-t intervals of rho as the cuts."""
        k = fit.n_points
        return cls(fit.theta_rad, fit.rho_m, fit.sigma_theta_rad,
                   abs(t_quantile(0.5 + 0.5 * CUT_MU1, k - 1)) * fit.sigma_rho_m,
                   abs(t_quantile(0.5 + 0.5 * CUT_MU0, k - 1)) * fit.sigma_rho_m,
                   fit.end_a.copy(), fit.end_b.copy(), float(t_s))

    @property
    def area_m(self) -> float:
        """Area of the trapezoid (height 1): ``rho0 + rho1``."""
        return self.rho0_m + self.rho1_m

    @property
    def length_m(self) -> float:
        return float(np.linalg.norm(self.end_b - self.end_a))

    @property
    def sigma_theta_total_rad(self) -> float:
        """Angle standard deviation with the heading's: ``sqrt(sigma_theta^2 + sigma_psi^2)``."""
        return math.hypot(self.sigma_theta_rad, self.sigma_heading_rad)

    def with_heading_uncertainty(self, pivot: FloatArray, sigma_psi_rad: float) -> "FuzzySegment":
        """This segment seen from a vehicle at ``pivot`` (2,) whose heading has standard deviation
        ``sigma_psi_rad``: rho cuts widened by ``(1, 1.96) sigma_psi L`` (module docstring)."""
        tangent = np.array([-math.sin(self.theta_rad), math.cos(self.theta_rad)])
        pv = np.asarray(pivot, dtype=float)
        lever = max(abs(float((self.end_a - pv) @ tangent)), abs(float((self.end_b - pv) @ tangent)))
        g = sigma_psi_rad * lever
        out = self.grown(g, 1.96 * g)
        return FuzzySegment(out.theta_rad, out.rho_m, out.sigma_theta_rad, out.rho1_m, out.rho0_m, out.end_a,
                            out.end_b, out.t_s, max(self.sigma_heading_rad, float(sigma_psi_rad)))

    @property
    def normal(self) -> FloatArray:
        return np.array([math.cos(self.theta_rad), math.sin(self.theta_rad)])

    def grown(self, extra_rho1_m: float, extra_rho0_m: float) -> "FuzzySegment":
        """Bounded sum with a centred trapezoid ``(-extra0, -extra1, extra1, extra0)`` (eq. 12)."""
        return FuzzySegment(self.theta_rad, self.rho_m, self.sigma_theta_rad, self.rho1_m + extra_rho1_m,
                            self.rho0_m + extra_rho0_m, self.end_a, self.end_b, self.t_s, self.sigma_heading_rad)

    def shifted(self, offset_ne_m: FloatArray) -> "FuzzySegment":
        """The segment moved by ``offset_ne_m`` (2,): ``rho + n . offset``, ends moved; the normal
        turned by pi when rho would fall below 0 (so ``rho >= 0``)."""
        off = np.asarray(offset_ne_m, dtype=float).reshape(2)
        rho, theta = self.rho_m + float(self.normal @ off), self.theta_rad
        if rho < 0.0:
            rho, theta = -rho, float(wrap_angle(theta + math.pi))
        return replace(self, theta_rad=theta, rho_m=rho, end_a=self.end_a + off, end_b=self.end_b + off)

    def rotated(self, angle_rad: float) -> "FuzzySegment":
        """The segment turned by ``angle_rad`` about its frame's origin (north towards east):
        ``theta + angle``, rho unchanged, ends rotated."""
        c, s_ = math.cos(angle_rad), math.sin(angle_rad)
        R = np.array([[c, -s_], [s_, c]])
        return replace(self, theta_rad=float(wrap_angle(self.theta_rad + angle_rad)), end_a=R @ self.end_a,
                       end_b=R @ self.end_b)

    def oriented_like(self, other: "FuzzySegment") -> "FuzzySegment":
        """The same line with its normal on ``other``'s side (``theta + pi``, ``-rho`` if needed)."""
        if self.normal @ other.normal >= 0.0:
            return self
        return replace(self, theta_rad=float(wrap_angle(self.theta_rad + math.pi)), rho_m=-self.rho_m)

    def matching_degree(self, other: "FuzzySegment", max_angle_rad: float) -> float:
        """Matching degree (eq. 17) of the rho trapezoids, ``other`` turned to this normal's side;
        0 when the normals differ by more than ``max_angle_rad``."""
        o = other.oriented_like(self)
        if abs(float(wrap_angle(self.theta_rad - o.theta_rad))) > max_angle_rad:
            return 0.0
        return matching_degree(self.rho_m, self.rho1_m, self.rho0_m, o.rho_m, o.rho1_m, o.rho0_m)

    def matches(self, other: "FuzzySegment", max_angle_rad: float, min_match: float) -> bool:
        """Collinearity test (eq. 16)."""
        return self.matching_degree(other, max_angle_rad) >= min_match

    def fused(self, other: "FuzzySegment") -> "FuzzySegment":
        """The fusion of two collinear segments (eqs. 18-19, module docstring), in this one's
        normal orientation."""
        other = other.oriented_like(self)
        va, vb = max(self.rho0_m, 1e-9) ** 2, max(other.rho0_m, 1e-9) ** 2
        wa, wb = 1.0 / va, 1.0 / vb
        dth = float(wrap_angle(other.theta_rad - self.theta_rad))
        sa, sb = max(self.sigma_theta_rad, 1e-9) ** 2, max(other.sigma_theta_rad, 1e-9) ** 2
        theta = float(wrap_angle(self.theta_rad + dth * sa / (sa + sb)))
        n = np.array([math.cos(theta), math.sin(theta)])
        rho_a = self.rho_m + float((n - self.normal) @ (0.5 * (self.end_a + self.end_b)))
        rho_b = other.rho_m + float((n - other.normal) @ (0.5 * (other.end_a + other.end_b)))
        rho = (wa * rho_a + wb * rho_b) / (wa + wb)
        tangent = np.array([-n[1], n[0]])
        ends = np.array([self.end_a, self.end_b, other.end_a, other.end_b])
        t = ends @ tangent
        foot = rho * n
        comb = lambda a, b: 1.0 / math.sqrt(1.0 / max(a, 1e-12) ** 2 + 1.0 / max(b, 1e-12) ** 2)  # noqa: E731
        return FuzzySegment(theta, float(rho), math.sqrt(sa * sb / (sa + sb)), comb(self.rho1_m, other.rho1_m),
                            comb(self.rho0_m, other.rho0_m), foot + t.min() * tangent, foot + t.max() * tangent,
                            max(self.t_s, other.t_s), max(self.sigma_heading_rad, other.sigma_heading_rad))


class FuzzySegmentMap:
    """The persistent local map of fuzzy segments around the vehicle ([P002] Fig. 10).

    Segments live in a vehicle-centred frame (north, east axes, origin at the vehicle's body
    origin), so a correction of the vehicle's absolute position leaves them in place. Then:

    * :meth:`move`: the vehicle moved by ``delta_ne_m`` (its motion estimate) over ``dt_s``:
      every segment shifts by ``-delta`` (``rho' = rho - n . delta``, kept ``>= 0`` by turning
      the normal) and its rho trapezoid takes the bounded sum (eq. 12) of a motion trapezoid
      ``(-m0, -m1, m1, m0)``, ``m0 = motion_growth |delta|``, and an age trapezoid
      ``(-a0, -a1, a1, a0)``, ``a0 = age_growth_mps dt``, with ``x1 = x0 / 1.96`` (the 68 % and
      95 % cuts of a Gaussian); segments whose trapezoid area ``rho0 + rho1`` then exceeds
      ``max_area_m`` are removed.
    * :meth:`add`: a new segment fuses (eqs. 18-19) with the stored segment it is collinear
      with (eq. 16: normals within ``max_angle_rad``, matching degree at least ``min_match``)
      with the highest matching degree, and the result again with any other it is now
      collinear with; otherwise it joins the map.

    Args:
        max_angle_rad: collinearity angle limit; min_match: matching-degree limit (eq. 16).
        motion_growth: 95 % rho-cut growth per metre travelled (m/m); age_growth_mps: per second.
        max_area_m: removal threshold on the trapezoid area, m.
    """

    def __init__(self, max_angle_rad: float = math.radians(5.0), min_match: float = 0.3, motion_growth: float = 0.02,
                 age_growth_mps: float = 0.002, max_area_m: float = 1.0) -> None:
        self.max_angle_rad = max_angle_rad
        self.min_match = min_match
        self.motion_growth = motion_growth
        self.age_growth_mps = age_growth_mps
        self.max_area_m = max_area_m
        self.segments: list[FuzzySegment] = []

    def clear(self) -> None:
        self.segments = []

    def move(self, delta_ne_m: FloatArray, dt_s: float) -> None:
        """The vehicle moved by ``delta_ne_m`` (2,) m in ``dt_s`` s: shift, grow, remove (class docstring)."""
        delta = np.asarray(delta_ne_m, dtype=float).reshape(2)
        g0 = self.motion_growth * float(np.hypot(*delta)) + self.age_growth_mps * max(float(dt_s), 0.0)
        self.segments = [s.shifted(-delta).grown(g0 / 1.96, g0) for s in self.segments]
        self.segments = [s for s in self.segments if s.area_m <= self.max_area_m]

    def rotate(self, angle_rad: float) -> None:
        """Turn every segment by ``angle_rad`` about the vehicle (a correction of the heading the
        map was built with)."""
        self.segments = [s.rotated(angle_rad) for s in self.segments]

    def _best_match(self, seg: FuzzySegment, skip: int = -1) -> int:
        best, best_deg = -1, -1.0
        for i, s in enumerate(self.segments):
            if i == skip:
                continue
            deg = s.matching_degree(seg, self.max_angle_rad)
            if deg >= self.min_match and deg > best_deg:
                best, best_deg = i, deg
        return best

    def add(self, seg: FuzzySegment) -> FuzzySegment:
        """Fuse ``seg`` into the map or add it (class docstring). Returns the stored segment."""
        i = self._best_match(seg)
        if i < 0:
            self.segments.append(seg)
            return seg
        self.segments[i] = self.segments[i].fused(seg)
        while (j := self._best_match(self.segments[i], skip=i)) >= 0:  # the fusion may now join another
            merged = self.segments[i].fused(self.segments[j])
            keep = min(i, j)
            self.segments = [s for k, s in enumerate(self.segments) if k not in (i, j)]
            self.segments.insert(keep, merged)
            i = keep
        return self.segments[i]
