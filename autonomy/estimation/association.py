"""K-best data associator (the data-associator role) for multiple-hypothesis tracking.

Each measurement of a scan may come from one of the objects a hypothesis holds (shared
labels >= 0, at most one measurement each) or from a private origin of its own (negative
labels: new object, clutter). Costs are negative log weights. For every hypothesis the
associator yields its joint associations best first, exactly (Murty 1968, as used for MHT by
Cox and Miller 1995), via :func:`autonomy.estimation.assignment.ranked_associations`.
Hypotheses offering the same gated options share one lazily extended ranked list.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from autonomy.estimation.assignment import LazyRanked, ranked_associations

Option = tuple[int, float]  # (label, cost)


class KBestAssociator:
    """Ranked associations of one scan.

    Args:
        gated: per measurement, the ``(object label >= 0, cost)`` pairs inside the gate, over
            all objects of all hypotheses.
        private: per measurement, its ``(label < 0, cost)`` private origins.
    """

    def __init__(self, gated: Sequence[Sequence[Option]], private: Sequence[Sequence[Option]]) -> None:
        if len(gated) != len(private):
            raise ValueError(f"KBestAssociator: {len(gated)} gated rows but {len(private)} private rows")
        self._private = [tuple(pv) for pv in private]
        #: Rows with gated objects: (row, its gated options, its private options).
        self._gated_rows = [(j, tuple(g), pv) for j, (g, pv) in enumerate(zip(gated, self._private)) if g]
        #: Every object label gated with some measurement: a hypothesis's options depend only on
        #: which of these it holds, so that set keys the shared streams.
        self._gated_labels = frozenset(o[0] for g in gated for o in g)
        self._streams: dict[frozenset[int], LazyRanked] = {}
        self._row_cache: dict = {}

    def ranked(self, labels: Iterable[int]) -> LazyRanked:
        """Joint associations, best first, of a hypothesis holding the objects ``labels``:
        ``get(k)`` gives the k-th ``(total cost, label of each measurement)`` or None."""
        present = self._gated_labels.intersection(labels)
        stream = self._streams.get(present)
        if stream is None:
            opts = list(self._private)
            if present:
                for j, g, pv in self._gated_rows:
                    opts[j] = tuple([o for o in g if o[0] in present]) + pv
            stream = self._streams[present] = LazyRanked(ranked_associations(opts, self._row_cache))
        return stream
