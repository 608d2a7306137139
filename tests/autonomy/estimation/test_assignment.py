"""Ranked assignments and the k-best associator against brute-force enumeration."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment
from scipy.sparse.csgraph import connected_components

from autonomy.estimation.assignment import _row_groups, murty_k_best, ranked_associations
from autonomy.estimation.association import KBestAssociator


def test_murty_matches_brute_force_ranking():
    rng = np.random.default_rng(1)
    for _ in range(150):
        m = int(rng.integers(1, 5))
        n = int(rng.integers(m, 7))
        C = rng.normal(size=(m, n))
        C[rng.random((m, n)) < 0.3] = np.inf
        brute = sorted(sum(C[i, p[i]] for i in range(m)) for p in itertools.permutations(range(n), m))
        brute = [b for b in brute if np.isfinite(b)]
        got = list(murty_k_best(C))
        np.testing.assert_allclose([c for c, _ in got], brute)
        assert len({tuple(cols) for _, cols in got}) == len(got)  # no solution twice


def test_sparse_ranked_associations_match_brute_force():
    rng = np.random.default_rng(2)
    for _ in range(200):
        m, n_labels = int(rng.integers(0, 5)), int(rng.integers(0, 4))
        options = []
        for _j in range(m):
            row = [(-1, float(rng.normal())), (-2, float(rng.normal()))]
            row += [(lab, float(rng.normal())) for lab in range(n_labels) if rng.random() < 0.5]
            options.append(row)
        brute = []
        for combo in itertools.product(*options):
            shared = [lab for lab, _ in combo if lab >= 0]
            if len(shared) == len(set(shared)):
                brute.append((sum(c for _, c in combo), tuple(lab for lab, _ in combo)))
        got = list(ranked_associations(options, row_cache={}))
        np.testing.assert_allclose([c for c, _ in got], sorted(c for c, _ in brute))
        assert {labels for _, labels in got} == {labels for _, labels in brute}


def test_associator_ranks_each_hypothesis_like_brute_force_over_its_objects():
    """A hypothesis holding objects ``held`` may only use those labels; its ranked list is
    the brute-force ranking of the options restricted to them, shared between hypotheses
    holding the same gated objects."""
    rng = np.random.default_rng(3)
    for _ in range(60):
        m, n_labels = int(rng.integers(1, 4)), int(rng.integers(1, 5))
        gated = [[(lab, float(rng.normal())) for lab in range(n_labels) if rng.random() < 0.6] for _ in range(m)]
        private = [[(-1, float(rng.normal())), (-2, float(rng.normal()))] for _ in range(m)]
        assoc = KBestAssociator(gated, private)
        held = frozenset(lab for lab in range(n_labels) if rng.random() < 0.7)
        stream = assoc.ranked(held)
        got, k = [], 0
        while (item := stream.get(k)) is not None:
            got.append(item)
            k += 1
        rows = [[o for o in g if o[0] in held] + p for g, p in zip(gated, private)]
        brute = []
        for combo in itertools.product(*rows):
            shared = [lab for lab, _ in combo if lab >= 0]
            if len(shared) == len(set(shared)):
                brute.append((sum(c for _, c in combo), tuple(lab for lab, _ in combo)))
        np.testing.assert_allclose([c for c, _ in got], sorted(c for c, _ in brute))
        assert {labels for _, labels in got} == {labels for _, labels in brute}
        assert assoc.ranked(held | {n_labels + 5}) is stream  # an ungated extra object changes nothing


def _brute(options):
    out = []
    for combo in itertools.product(*options):
        shared = [lab for lab, _ in combo if lab >= 0]
        if len(shared) == len(set(shared)):
            out.append((sum(c for _, c in combo), tuple(lab for lab, _ in combo)))
    return out


def test_linked_and_single_row_groups_match_brute_force_and_scipy_optimum():
    """Scans mixing rows that share labels (ranked by Murty) with rows of their own: the
    product walk over the groups gives every joint assignment once, best first, and the best
    is scipy's optimal assignment of the full cost matrix (one column per shared label, one
    per private option)."""
    rng = np.random.default_rng(4)
    n_linked = 0
    for _ in range(150):
        m, n_labels = int(rng.integers(2, 6)), int(rng.integers(1, 6))
        options = []
        for _j in range(m):
            row = [(-2, float(rng.normal(1.0)))] + ([(-1, float(rng.normal(1.0)))] if rng.random() < 0.7 else [])
            row += [(lab, float(rng.normal())) for lab in range(n_labels) if rng.random() < 0.35]
            options.append(row)
        n_linked += any(len(g) > 1 for g in _row_groups(options))
        got = list(ranked_associations(options, row_cache={}))
        brute = _brute(options)
        assert [c for c, _ in got] == pytest.approx(sorted(c for c, _ in brute))
        assert sorted(labels for _, labels in got) == sorted(labels for _, labels in brute)
        assert all(a[0] <= b[0] + 1e-12 for a, b in zip(got, got[1:]))
        cols = {}
        for j, row in enumerate(options):
            for lab, _ in row:
                cols.setdefault(lab if lab >= 0 else (j, lab), len(cols))
        C = np.full((m, len(cols)), 1e9)
        for j, row in enumerate(options):
            for lab, c in row:
                C[j, cols[lab if lab >= 0 else (j, lab)]] = c
        r, c = linear_sum_assignment(C)
        assert got[0][0] == pytest.approx(C[r, c].sum())
    assert n_linked > 50  # the linked (Murty) path was exercised


def test_row_groups_are_the_connected_components_of_shared_labels():
    rng = np.random.default_rng(5)
    for _ in range(200):
        m, n_labels = int(rng.integers(1, 8)), int(rng.integers(0, 8))
        options = [[(-2, 0.0)] + [(lab, 0.0) for lab in range(n_labels) if rng.random() < 0.25] for _ in range(m)]
        A = np.zeros((m, m), dtype=bool)
        for i in range(m):
            for j in range(m):
                A[i, j] = bool({lab for lab, _ in options[i] if lab >= 0} & {lab for lab, _ in options[j] if lab >= 0})
        n_comp, comp = connected_components(A, directed=False)
        expected = sorted((sorted(np.flatnonzero(comp == k).tolist()) for k in range(n_comp)), key=min)
        assert _row_groups(options) == expected
