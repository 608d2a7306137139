"""Disjoint-set forest with path halving and union by size."""

from __future__ import annotations

import numpy as np


class UnionFind:
    """``n`` singletons; ``union(i, j)`` merges, ``labels()`` gives a compact set id per item."""

    def __init__(self, n: int) -> None:
        self.parent = list(range(n))
        self.size = [1] * n

    def find(self, i: int) -> int:
        p = self.parent
        while p[i] != i:
            p[i] = p[p[i]]
            i = p[i]
        return i

    def union(self, i: int, j: int) -> bool:
        """Merge the sets of ``i`` and ``j``; False if they were already one set."""
        ri, rj = self.find(i), self.find(j)
        if ri == rj:
            return False
        if self.size[ri] < self.size[rj]:
            ri, rj = rj, ri
        self.parent[rj] = ri
        self.size[ri] += self.size[rj]
        return True

    def labels(self) -> np.ndarray:
        roots = [self.find(i) for i in range(len(self.parent))]
        _, lab = np.unique(roots, return_inverse=True)
        return lab.astype(np.int64)
