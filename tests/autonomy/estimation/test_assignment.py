"""Ranked assignments and the k-best associator against brute-force enumeration."""

from __future__ import annotations

import itertools

import numpy as np

from autonomy.estimation.assignment import murty_k_best, ranked_associations
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
