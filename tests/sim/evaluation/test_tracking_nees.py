"""Horizontal NEES of the tracking evaluation: hand algebra and the chi-square(2) law."""

from __future__ import annotations

import numpy as np
from scipy.stats import chi2

from sim.evaluation.tracking_eval import NEES2_95, horizontal_nees


def test_horizontal_nees_is_the_mahalanobis_square():
    P = np.array([[0.09, 0.03], [0.03, 0.04]])
    e = np.array([0.3, -0.1])
    det = 0.09 * 0.04 - 0.03**2
    expect = (0.04 * 0.3**2 - 2 * 0.03 * 0.3 * -0.1 + 0.09 * 0.1**2) / det  # e^T adj(P) e / det(P)
    assert abs(horizontal_nees(e, P) - expect) < 1e-12
    assert np.isnan(horizontal_nees(e, np.zeros((2, 2))))


def test_consistent_errors_give_the_chi_square_figures():
    """Errors drawn from the covariance itself: mean NEES ~ 2 and ~5 % above the 95 % point."""
    rng = np.random.default_rng(1)
    P = np.array([[0.25, -0.1], [-0.1, 0.16]])
    L = np.linalg.cholesky(P)
    v = np.array([horizontal_nees(L @ rng.standard_normal(2), P) for _ in range(4000)])
    assert abs(NEES2_95 - chi2.ppf(0.95, 2)) < 1e-12
    assert abs(v.mean() - 2.0) < 0.15 and abs(np.mean(v > NEES2_95) - 0.05) < 0.015
