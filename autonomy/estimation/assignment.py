"""Ranked assignments: Murty's k-best algorithm over ``scipy.optimize.linear_sum_assignment``.

Rows (measurements) must all be assigned, each to a distinct column; ``inf`` marks a
forbidden pair. Solutions come out in non-decreasing cost order, lazily.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Iterator, Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

FloatArray = NDArray[np.float64]


def _solve(cost: FloatArray) -> tuple[float, NDArray[np.intp]] | None:
    """Best full row assignment of ``cost`` (rows <= cols) or None when infeasible."""
    try:
        rows, cols = linear_sum_assignment(cost)
    except ValueError:  # no finite assignment exists
        return None
    total = float(cost[rows, cols].sum())
    if not np.isfinite(total) or rows.size != cost.shape[0]:
        return None
    return total, cols


def murty_k_best(cost: FloatArray) -> Iterator[tuple[float, NDArray[np.intp]]]:
    """Yield ``(total_cost, col_of_row (n_rows,))`` in order of increasing cost.

    Murty (1968): after reporting solution S of a subproblem, partition the subproblem into
    n_rows children, child i forcing S's first i pairs and forbidding its i-th pair.
    Forcing row i to column c is done by making every other entry of row i and column c
    infinite, so each child is again a plain assignment problem.
    """
    cost = np.asarray(cost, dtype=float)
    n_rows = cost.shape[0]
    if n_rows == 0:
        yield 0.0, np.zeros(0, dtype=np.intp)
        return
    first = _solve(cost)
    if first is None:
        return
    counter = 0
    # entries: (cost, tie-break, solution cols, constrained matrix, n forced leading rows)
    heap: list[tuple[float, int, NDArray[np.intp], FloatArray, int]] = [
        (first[0], counter, first[1], cost, 0)
    ]
    while heap:
        total, _, cols, mat, n_fixed = heapq.heappop(heap)
        yield total, cols
        forced = mat
        for i in range(n_fixed, n_rows):
            child = forced.copy()
            child[i, cols[i]] = np.inf
            sol = _solve(child)
            if sol is not None:
                counter += 1
                heapq.heappush(heap, (sol[0], counter, sol[1], child, i))
            if i + 1 < n_rows:
                forced = forced.copy()
                c = cols[i]
                keep = forced[i, c]
                forced[i, :] = np.inf
                forced[:, c] = np.inf
                forced[i, c] = keep


class LazyRanked:
    """Cached prefix of a ranked solution stream, extended on demand."""

    __slots__ = ("_items", "_gen")

    def __init__(self, gen: Iterator[tuple[float, tuple[int, ...]]]) -> None:
        self._items: list[tuple[float, tuple[int, ...]]] = []
        self._gen: Iterator[tuple[float, tuple[int, ...]]] | None = gen

    def get(self, i: int) -> tuple[float, tuple[int, ...]] | None:
        items = self._items
        if i < len(items):  # the common case: already drawn
            return items[i]
        gen = self._gen
        while gen is not None and len(items) <= i:
            nxt = next(gen, None)
            if nxt is None:
                self._gen = gen = None
            else:
                items.append(nxt)
        return items[i] if i < len(items) else None


def _component_stream(
    rows: list[int], options: Sequence[Sequence[tuple[int, float]]]
) -> Iterator[tuple[float, tuple[int, ...]]]:
    """Ranked label tuples of rows that share labels: Murty on their small cost matrix."""
    labels: list[int] = []
    col_of: dict[tuple[int, int], int] = {}  # (row or -1 for shared, label) -> column
    for r in rows:
        for lab, _ in options[r]:
            key = (-1, lab) if lab >= 0 else (r, lab)
            if key not in col_of:
                col_of[key] = len(labels)
                labels.append(lab)
    cost = np.full((len(rows), len(labels)), np.inf)
    for i, r in enumerate(rows):
        for lab, c in options[r]:
            cost[i, col_of[(-1, lab) if lab >= 0 else (r, lab)]] = c
    for total, cols in murty_k_best(cost):
        yield total, tuple(labels[c] for c in cols)


def _row_groups(options: Sequence[Sequence[tuple[int, float]]]) -> list[list[int]]:
    """Rows linked by a shared label (union-find), each group's rows ascending, groups in
    order of their first row."""
    n = len(options)
    owner: dict[int, int] = {}
    linked = False
    for j, opts in enumerate(options):
        for lab, _ in opts:
            if lab >= 0:
                if owner.setdefault(lab, j) != j:
                    linked = True
    if not linked:  # the common case: every row its own group
        return [[j] for j in range(n)]
    parent = list(range(n))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    owner.clear()
    for j, opts in enumerate(options):
        for lab, _ in opts:
            if lab >= 0:
                if lab in owner:
                    parent[find(j)] = find(owner[lab])
                else:
                    owner[lab] = j
    groups: dict[int, list[int]] = {}
    for j in range(n):
        groups.setdefault(find(j), []).append(j)
    return list(groups.values())


def ranked_associations(
    options: Sequence[Sequence[tuple[int, float]]],
    row_cache: dict | None = None,
) -> Iterator[tuple[float, tuple[int, ...]]]:
    """Exact k-best joint assignments, best first, for sparse per-row options.

    ``options[j]`` lists ``(label, cost)`` pairs for row j. Labels >= 0 are shared columns
    (at most one row each); negative labels are private to their row (never conflict).
    Yields ``(total_cost, label_of_row)``. Rows are split into independent groups (rows
    linked by a shared label); groups of one row are sorted lists, larger groups are
    ranked by :func:`murty_k_best`, and the product of the groups' ranked lists is walked
    best-first, each index tuple reached from one parent so none repeats: a tuple's total
    is its parent's minus the raised group's old cost plus its new one, and ties are
    broken by the index tuple. ``row_cache`` (a dict shared between calls) memoises the
    sorted lists of one-row groups.
    """
    n = len(options)
    if n == 0:
        yield 0.0, ()
        return
    comps = _row_groups(options)
    # Per group: its ranked items (a complete list for one row; the growing prefix of a
    # LazyRanked for Murty groups) and the LazyRanked that extends it (None when complete).
    ranked_items: list[list[tuple[float, tuple[int, ...]]]] = []
    lazies: list[LazyRanked | None] = []
    for rows in comps:
        if len(rows) == 1:
            key = tuple(options[rows[0]])
            items = None if row_cache is None else row_cache.get(key)
            if items is None:
                items = sorted([(c, (lab,)) for lab, c in key if math.isfinite(c)])
                if row_cache is not None:
                    row_cache[key] = items
            if not items:
                return
            ranked_items.append(items)
            lazies.append(None)
        else:
            lazy = LazyRanked(_component_stream(rows, options))
            if lazy.get(0) is None:
                return
            ranked_items.append(lazy._items)
            lazies.append(lazy)
    n_c = len(comps)
    if n_c == 1:  # one group: its ranked list is the answer
        rows, items, lazy = comps[0], ranked_items[0], lazies[0]
        k = 0
        while k < len(items) or (lazy is not None and lazy.get(k) is not None):
            total, sol = items[k]
            labels = [0] * n
            for r, lab in zip(rows, sol):
                labels[r] = lab
            yield total, tuple(labels)
            k += 1
        return
    labels = [0] * n
    for rows, items in zip(comps, ranked_items):
        for r, lab in zip(rows, items[0][1]):
            labels[r] = lab
    # heap entries: (total, index tuple, last raised group, labels); the index tuples are
    # distinct, so the labels are never compared
    heap: list[tuple[float, tuple[int, ...], int, tuple[int, ...]]] = [
        (sum(items[0][0] for items in ranked_items), (0,) * n_c, 0, tuple(labels))
    ]
    pop, push = heapq.heappop, heapq.heappush
    while heap:
        total, idx, last, labels_t = pop(heap)
        yield total, labels_t
        for c in range(last, n_c):
            items = ranked_items[c]
            k = idx[c]
            if k + 1 >= len(items):
                lazy = lazies[c]
                if lazy is None or lazy.get(k + 1) is None:
                    continue
            nxt = items[k + 1]
            rows = comps[c]
            if len(rows) == 1:
                child = labels_t[: rows[0]] + nxt[1] + labels_t[rows[0] + 1 :]
            else:
                lab_list = list(labels_t)
                for r, lab in zip(rows, nxt[1]):
                    lab_list[r] = lab
                child = tuple(lab_list)
            push(heap, (total - items[k][0] + nxt[0], idx[:c] + (k + 1,) + idx[c + 1 :], c, child))
