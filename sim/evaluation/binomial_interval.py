"""Confidence interval of a binomial proportion, for the rates the evaluations report (the
share of bubble clusters a gate refuses, of true detections it keeps)."""

from __future__ import annotations

import math

from scipy.stats import binomtest


def proportion_ci95(k: int, n: int) -> tuple[float, float]:
    """Exact (Clopper-Pearson) two-sided 95 % confidence interval of a binomial proportion
    ``k / n`` (scipy's ``binomtest``); (nan, nan) when ``n`` is 0. Raises ValueError for
    ``k`` outside 0..n."""
    if n == 0:
        return math.nan, math.nan
    if not 0 <= k <= n:
        raise ValueError(f"proportion_ci95: k = {k} outside 0..{n}")
    ci = binomtest(int(k), int(n)).proportion_ci(0.95, method="exact")
    return float(ci.low), float(ci.high)
