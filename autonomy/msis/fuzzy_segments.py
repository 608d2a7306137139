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
* A segment whose trapezoid area ``rho0 + rho1`` exceeds a threshold is dropped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

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

    def matches(self, other: "FuzzySegment", max_angle_rad: float, min_match: float) -> bool:
        """Collinearity test (eq. 16)."""
        if abs(float(wrap_angle(self.theta_rad - other.theta_rad))) > max_angle_rad:
            return False
        return matching_degree(self.rho_m, self.rho1_m, self.rho0_m, other.rho_m, other.rho1_m,
                               other.rho0_m) >= min_match

    def fused(self, other: "FuzzySegment") -> "FuzzySegment":
        """The fusion of two collinear segments (eqs. 18-19, module docstring)."""
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
    """The local map of fuzzy segments ([P002] Fig. 10): new segments fuse with collinear ones
    or join; all grow with vehicle motion and age; too uncertain ones are removed.

    Args:
        max_angle_rad: collinearity angle limit; min_match: matching-degree limit (eq. 16).
        motion_growth: rho cut growth per metre travelled (m/m); age_growth_mps: per second.
        max_area_m: removal threshold on the trapezoid area.
    """

    def __init__(self, max_angle_rad: float = math.radians(5.0), min_match: float = 0.3, motion_growth: float = 0.02,
                 age_growth_mps: float = 0.002, max_area_m: float = 1.0) -> None:
        self.max_angle_rad = max_angle_rad
        self.min_match = min_match
        self.motion_growth = motion_growth
        self.age_growth_mps = age_growth_mps
        self.max_area_m = max_area_m
        self.segments: list[FuzzySegment] = []

    def grow(self, travelled_m: float, dt_s: float) -> None:
        """Add motion and age uncertainty to every segment, then drop those above the area limit."""
        g = self.motion_growth * travelled_m + self.age_growth_mps * dt_s
        self.segments = [s.grown(0.5 * g, g) for s in self.segments]
        self.segments = [s for s in self.segments if s.area_m <= self.max_area_m]

    def add(self, seg: FuzzySegment) -> FuzzySegment:
        """Fuse ``seg`` with the first collinear segment, or add it. Returns the stored segment."""
        for i, s in enumerate(self.segments):
            if s.matches(seg, self.max_angle_rad, self.min_match):
                self.segments[i] = s.fused(seg)
                return self.segments[i]
        self.segments.append(seg)
        return seg
