"""Line segments from ordered sonar points: IEPF, eigenvector line fit and Student-t
intervals of [P002] section 3.2.2.

* :func:`iepf_split` ([P002] IEPF steps 1-3): a run of ordered points is split at the point
  farthest from the chord between its ends while that distance is ``>= rho_max``; runs of
  fewer than ``k_min`` points are rejected.
* :func:`fit_line` (eigenvector fit): the line ``x cos(theta) + y sin(theta) = rho``
  (``rho >= 0``) whose normal is the eigenvector of the points' scatter matrix with the
  smallest eigenvalue, through their centroid; end points are the projections of the extreme
  points. ``sigma_rho = s / sqrt(k)`` with ``s^2 = sum d_i^2 / (k - 2)`` (d_i the signed
  distances), ``sigma_theta = s / sqrt(sum t_i^2)`` (t_i the positions along the line about the
  centroid; ``~ s sqrt(12 / k) / l`` for evenly spread points over a length ``l``).
* :func:`t_quantile`: Student's t quantile from the inverse regularised incomplete beta,
  for the ``rho +- t_{k-1; 1 - alpha/2} sigma_rho`` cuts of the fuzzy segments.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import betaincinv

FloatArray = NDArray[np.float64]


def t_quantile(p: float, dof: int) -> float:
    """Quantile ``t_{dof; p}`` of Student's t, ``0 < p < 1``: for ``p > 1/2``,
    ``sqrt(dof (1 / x - 1))`` with ``x = I^-1_{2 (1 - p)}(dof / 2, 1 / 2)`` (odd symmetry below).

    Raises:
        ValueError: ``p`` outside (0, 1) or ``dof < 1``.
    """
    if not 0.0 < p < 1.0 or dof < 1:
        raise ValueError(f"need 0 < p < 1 and dof >= 1, got p={p}, dof={dof}")
    if p == 0.5:
        return 0.0
    q = p if p > 0.5 else 1.0 - p
    x = float(betaincinv(0.5 * dof, 0.5, 2.0 * (1.0 - q)))
    t = math.sqrt(dof * (1.0 / x - 1.0))
    return t if p > 0.5 else -t


@dataclass(frozen=True, slots=True)
class LineFit:
    """A fitted line segment ``x cos(theta) + y sin(theta) = rho``.

    Attributes:
        theta_rad: normal direction (rad, in (-pi, pi]); rho_m: distance from the origin (>= 0).
        sigma_rho_m, sigma_theta_rad: standard deviations of rho and theta.
        end_a, end_b: (2,) end points (projections of the extreme points), m.
        n_points: k, the points fitted.
    """

    theta_rad: float
    rho_m: float
    sigma_rho_m: float
    sigma_theta_rad: float
    end_a: FloatArray
    end_b: FloatArray
    n_points: int

    @property
    def length_m(self) -> float:
        return float(np.linalg.norm(self.end_b - self.end_a))

    def rho_interval(self, confidence: float) -> float:
        """Half width ``|t_{k-1; 1 - alpha/2}| sigma_rho`` of the ``confidence`` interval, m."""
        return abs(t_quantile(0.5 + 0.5 * confidence, self.n_points - 1)) * self.sigma_rho_m


def fit_line(points: ArrayLike) -> LineFit:
    """Eigenvector (total least squares) line fit of (k, 2) points, k >= 3 (module docstring).

    Raises:
        ValueError: fewer than 3 points or all coincident.
    """
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    k = len(p)
    if k < 3:
        raise ValueError(f"a line fit needs at least 3 points, got {k}")
    c = p.mean(axis=0)
    q = p - c
    w, v = np.linalg.eigh(q.T @ q)
    if w[1] <= 0.0:
        raise ValueError("points are coincident: no line")
    n = v[:, 0]
    rho = float(n @ c)
    if rho < 0.0:
        n, rho = -n, -rho
    d = q @ n
    s = math.sqrt(float(d @ d) / max(k - 2, 1))
    tangent = np.array([-n[1], n[0]])
    t = q @ tangent
    sum_t2 = float(t @ t)
    foot = c - (c @ n - rho) * n
    return LineFit(theta_rad=float(math.atan2(n[1], n[0])), rho_m=rho, sigma_rho_m=s / math.sqrt(k),
                   sigma_theta_rad=s / math.sqrt(sum_t2) if sum_t2 > 0 else math.inf,
                   end_a=foot + t.min() * tangent, end_b=foot + t.max() * tangent, n_points=k)


def iepf_split(points: ArrayLike, k_min: int, rho_max_m: float) -> list[tuple[int, int]]:
    """Iterative End Point Fit on ordered (N, 2) points ([P002] IEPF).

    Returns:
        ``(start, stop)`` index ranges (stop exclusive, in order) of the runs that are line
        candidates: every point within ``rho_max_m`` of the chord between the run's ends and
        at least ``k_min`` points.

    Raises:
        ValueError: ``k_min < 2`` or a non-positive ``rho_max_m``.
    """
    if k_min < 2 or not rho_max_m > 0.0:
        raise ValueError(f"need k_min >= 2 and rho_max_m > 0, got {k_min}, {rho_max_m}")
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    out: list[tuple[int, int]] = []
    stack = [(0, len(p))]
    while stack:
        i0, i1 = stack.pop()
        if i1 - i0 < k_min:
            continue  # Step 1: reject
        a, b = p[i0], p[i1 - 1]
        ab = b - a
        L = float(np.hypot(*ab))
        seg = p[i0:i1] - a
        dist = np.abs(seg[:, 0] * ab[1] - seg[:, 1] * ab[0]) / L if L > 0 else np.hypot(seg[:, 0], seg[:, 1])
        j = int(np.argmax(dist))  # Step 2
        if dist[j] >= rho_max_m and 0 < j < i1 - i0 - 1:  # Step 3: split at P
            stack.append((i0 + j, i1))
            stack.append((i0, i0 + j + 1))
        elif dist[j] < rho_max_m:
            out.append((i0, i1))
    return sorted(out)
