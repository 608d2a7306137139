"""Loopy BP association against [P003] (section IV, ``docs/references.md``) and exact enumeration."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.mapping.data_association import exact_marginals, loopy_bp

REF = np.array([[1, 4, 0.5, 0], [1, 3, 2, 0.1], [1, 0, 1.5, 6]], dtype=float)


def test_reference_example():
    res = loopy_bp(REF)
    assert res.converged
    assert res.p_object[0] == pytest.approx([0.3324, 0.5979, 0.0697, 0.0], abs=2e-4)
    assert exact_marginals(REF)[0] == pytest.approx([0.3147, 0.5936, 0.0917, 0.0], abs=2e-4)


def test_small_random_cases_close_to_exact_enumeration():
    rng = np.random.default_rng(4)
    errs = []
    for _ in range(200):
        k, m = rng.integers(1, 5), rng.integers(1, 5)
        beta = np.concatenate([rng.uniform(0.2, 1.0, (k, 1)), rng.exponential(1.0, (k, m))], axis=1)
        beta[:, 1:][rng.random((k, m)) < 0.4] = 0.0  # gating
        xi = rng.uniform(0.5, 2.0, m)
        res = loopy_bp(beta, xi)
        assert res.converged
        errs.append(np.max(np.abs(res.p_object - exact_marginals(beta, xi))))
    errs = np.array(errs)
    assert np.median(errs) < 0.01 and errs.max() < 0.1  # BP is approximate on loopy graphs
    # a single object (a tree) is exact
    beta = np.array([[0.7, 2.0, 0.3, 1.1]])
    assert loopy_bp(beta, [1.0, 2.0, 0.5]).p_object == pytest.approx(exact_marginals(beta, [1.0, 2.0, 0.5]))


def test_bad_input():
    with pytest.raises(ValueError):
        loopy_bp([[0.0, 1.0]])
    with pytest.raises(ValueError):
        loopy_bp([[1.0, -1.0]])
