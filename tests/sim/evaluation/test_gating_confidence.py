"""The exact binomial interval the tracking study reports for its ROI gating figures, against
closed forms of the Clopper-Pearson bounds and the beta quantiles that define them."""

from __future__ import annotations

import math

import pytest
from scipy.stats import beta

from sim.evaluation.binomial_interval import proportion_ci95


def test_all_refused_has_the_closed_form_lower_bound():
    # k = n: upper 1, lower (alpha / 2)^(1 / n) (the probability of n successes in n is p^n)
    for n in (11, 14, 50):
        lo, hi = proportion_ci95(n, n)
        assert hi == pytest.approx(1.0) and lo == pytest.approx(0.025 ** (1.0 / n), rel=1e-9)
    lo, hi = proportion_ci95(0, 20)
    assert lo == pytest.approx(0.0, abs=1e-12) and hi == pytest.approx(1.0 - 0.025 ** (1.0 / 20), rel=1e-9)


@pytest.mark.parametrize("k,n", [(11, 14), (121, 141), (288, 320), (3, 40)])
def test_interval_is_the_beta_quantiles(k, n):
    lo, hi = proportion_ci95(k, n)
    assert lo == pytest.approx(beta.ppf(0.025, k, n - k + 1), rel=1e-7)
    assert hi == pytest.approx(beta.ppf(0.975, k + 1, n - k), rel=1e-7)
    assert lo < k / n < hi


def test_empty_and_bad_counts():
    assert all(math.isnan(v) for v in proportion_ci95(0, 0))
    with pytest.raises(ValueError, match="outside"):
        proportion_ci95(5, 4)
