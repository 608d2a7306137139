"""Per-step series of a rerun recording sent as columns: the values of one entity are kept in
preallocated arrays and sent with ``send_columns`` as one chunk every ``capacity`` rows.

Logging a value per mission step with ``rr.log`` makes one pending row per call in the SDK's
batcher (several kB each with its own Arrow arrays) until the next flush, and the mission's
step-rate series (vehicle pose, navigation errors at 10 Hz) are three quarters of a
recording's rows; the batcher's pending rows and the allocations they leave behind were most of
the recorder's memory. Sent as columns, a series costs ``capacity`` x (width + 1) numbers and
its chunks have a fixed length in rows, whatever the wall-clock speed of the run. The rows
(entity, ``sim_time``, values, component types) are those ``rr.log`` with ``rr.set_time(...,
duration=t_s)`` would give.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np


def duration_ns(t_s: float) -> int:
    """``t_s`` (s) as the integer nanoseconds ``rr.set_time(..., duration=t_s)`` stores."""
    return round(1e9 * float(t_s))


class _Column(ABC):
    """Rows (time, ``width`` values) of one entity buffered until ``capacity`` are held; a
    subclass says which rerun archetype's columns they are (:meth:`_columns`)."""

    width = 1

    def __init__(self, entity: str, capacity: int, timeline: str = "sim_time") -> None:
        if capacity < 1:
            raise ValueError(f"capacity {capacity}: must be >= 1")
        self.entity, self.timeline = entity, timeline
        self._t_ns = np.empty(capacity, dtype=np.int64)
        self._v = np.empty((capacity, self.width), dtype=float)
        self._n = 0
        self.n_sent_chunks = 0

    def __len__(self) -> int:
        return self._n

    def append(self, rec, rr, t_s: float, values) -> None:
        """Add one row at ``t_s`` (s); sends the buffer to ``rec`` once it is full."""
        self._t_ns[self._n] = duration_ns(t_s)
        self._v[self._n] = values
        self._n += 1
        if self._n == len(self._t_ns):
            self.send(rec, rr)

    def send(self, rec, rr) -> None:
        """Send the rows held (if any) as one ``send_columns`` chunk and empty the buffer."""
        n = self._n
        if not n:
            return
        times = rr.TimeColumn(self.timeline, duration=self._t_ns[:n].astype("timedelta64[ns]"))
        rec.send_columns(self.entity, indexes=[times], columns=self._columns(rr, self._v[:n]))
        self._n = 0
        self.n_sent_chunks += 1

    @abstractmethod
    def _columns(self, rr, v: np.ndarray):
        """The archetype's component columns of the rows ``v`` ((n, width))."""


class ScalarColumn(_Column):
    """``rr.Scalars`` of one value a row (e.g. a navigation error, m)."""

    def _columns(self, rr, v: np.ndarray):
        return rr.Scalars.columns(scalars=v[:, 0].copy())


class PoseColumn(_Column):
    """``rr.Transform3D`` of a translation (3,) and a quaternion (x, y, z, w) a row."""

    width = 7

    def _columns(self, rr, v: np.ndarray):
        return rr.Transform3D.columns(translation=v[:, :3].copy(), quaternion=v[:, 3:].copy())
