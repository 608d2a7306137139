"""Scoring: GOSPA against worked examples of [Rahmathullah2017] and brute force; matching."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from sim.evaluation.world_model_score import gospa, match, score_world_model

TRUTHS = [(0.0, 0.0), (10.0, 0.0), (20.0, 0.0)]
ESTIMATES = [(0.0, 1.0), (10.0, 0.5), (50.0, 50.0)]


@pytest.mark.parametrize(("p", "c", "expected"), [(1, 10, 11.5), (2, 10, 10.0623), (2, 5, 5.1235)])
def test_gospa_reference_worked_examples(p, c, expected):
    assert gospa(ESTIMATES, TRUTHS, c=c, p=p) == pytest.approx(expected, abs=1e-4)


def _gospa_brute(x, y, c, p):
    """Minimum over all partial assignments, unassigned points costing c^p / 2 each."""
    x, y = np.asarray(x, float).reshape(-1, 2), np.asarray(y, float).reshape(-1, 2)
    best = np.inf
    for k in range(min(len(x), len(y)) + 1):
        for xs in itertools.combinations(range(len(x)), k):
            for ys in itertools.permutations(range(len(y)), k):
                d = sum(np.linalg.norm(x[i] - y[j]) ** p for i, j in zip(xs, ys))
                if all(np.linalg.norm(x[i] - y[j]) <= c for i, j in zip(xs, ys)):
                    best = min(best, d + 0.5 * c**p * (len(x) + len(y) - 2 * k))
    return best ** (1.0 / p)


def test_gospa_matches_brute_force_on_random_sets():
    rng = np.random.default_rng(0)
    for _ in range(60):
        x = rng.uniform(0, 6, (int(rng.integers(0, 5)), 2))
        y = rng.uniform(0, 6, (int(rng.integers(0, 5)), 2))
        c, p = float(rng.uniform(0.5, 3)), float(rng.choice([1, 2]))
        assert gospa(x, y, c=c, p=p) == pytest.approx(_gospa_brute(x, y, c, p))


def test_match_prefers_more_pairs_within_gate_and_score_counts():
    truths = np.array([[0.0, 0.0, 4.0], [3.0, 0.0, 4.0], [10.0, 10.0, 4.0]])
    est = np.array([[1.6, 0.0, 4.2], [4.5, 0.0, 3.0], [30.0, 0.0, 4.0]])
    pairs = match(est[:, :2], truths[:, :2], max_dist_m=2.0)
    assert sorted((i, j) for i, j, _ in pairs) == [(0, 0), (1, 1)]
    s = score_world_model(est, truths)
    assert (s["objects"], s["matched"], s["missed"], s["false"]) == (3, 2, 1, 1)
    assert s["mean_position_error_m"] == pytest.approx((1.6 + 1.5) / 2)
    assert s["gospa"] == pytest.approx(1.6 + 1.5 + 1.0 + 1.0)  # c = 2, p = 1
    s3 = score_world_model(est, truths, horizontal=False)
    assert s3["mean_position_error_m"] > s["mean_position_error_m"]


def test_empty_sets():
    assert gospa(np.zeros((0, 2)), TRUTHS, c=2.0) == pytest.approx(3.0)
    s = score_world_model(np.zeros((0, 3)), np.zeros((0, 3)))
    assert s["matched"] == 0 and s["gospa"] == 0.0 and np.isnan(s["mean_position_error_m"])


def test_world_model_metrics_report_each_targets_nees_and_the_chi_square_band():
    from scipy.stats import chi2

    from autonomy.world_model.pmha import WorldObject
    from sim.features.perception import world_model_metrics

    truth = np.array([[0.0, 0.0, 5.0], [10.0, 0.0, 5.0]])
    target = np.array([0.99, 0.01])
    objs = [WorldObject(1, target, np.array([0.9, -0.8, 5.0]), np.diag([0.09, 0.04, 1.0]), 5, 1.0),
            WorldObject(2, target, np.array([10.0, 0.2, 5.0]), np.array([[0.05, 0.01, 0], [0.01, 0.02, 0], [0, 0, 1]]),
                        5, 1.0)]
    m = world_model_metrics(objs, truth)
    by_id = {p["estimate_id"]: p["nees"] for p in m["pairs"]}
    # hand algebra: 0.9^2 / 0.09 + 0.8^2 / 0.04 = 25; e^T P^-1 e with P = [[.05 .01] [.01 .02]], e = (0, .2)
    assert by_id[1] == pytest.approx(25.0)
    assert by_id[2] == pytest.approx(0.2**2 * 0.05 / (0.05 * 0.02 - 0.01**2))
    s = m["nees_horizontal"]
    assert s["n"] == 2 and s["mean"] == pytest.approx((by_id[1] + by_id[2]) / 2)
    assert s["band_95"] == pytest.approx([chi2.ppf(0.025, 4) / 2, chi2.ppf(0.975, 4) / 2])
    assert s["within_band"] is False  # mean 13.6 > 5.57
    assert s["above_95_fraction"] == pytest.approx(0.5)  # 25 > 5.99 > 2.22
