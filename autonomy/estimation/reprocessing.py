"""Out-of-sequence measurements by re-processing (the reprocessing role): a time-ordered event
history with stored estimator states, so that an event older than the newest is applied at
its own time and everything after it is applied again.

A measurement that reaches a filter after newer ones (a USBL fix computed on the surface and
sent down an acoustic link; a fix late by its acoustic travel time) describes the past.
Re-processing keeps every event the estimator applied, in time order, and copies of the
estimator's state before some of them (checkpoints): a late event rolls the estimator back to
the last checkpoint before its time, replays the events up to that time, applies the late
event there and replays the rest. The result is the estimate the filter would have had with
the event on time, exactly, for the same sequence of events ([BarShalom2001-OOSM] section
10.8, docs/references.md).

:class:`ReprocessingHistory` is the one implementation: the estimator supplies how to apply an
event to its live state, how to copy and restore that state and its clock; the history
decides when to checkpoint and what to replay. The vehicle's navigation filter with late
fixes (:class:`autonomy.navigation.delayed.DelayedFixFilter`, a checkpoint per
``checkpoint_every_s`` of filter time) and the target tracker
(:class:`autonomy.tracking.tracker.TargetTracker`, a checkpoint before every event) use it.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable, Sequence
from typing import Any, Generic, TypeVar

E = TypeVar("E")  # an event (a message, a measurement)
S = TypeVar("S")  # a copy of the estimator's state


class ReprocessingHistory(Generic[E, S]):
    """Events in time order with checkpoints of the estimator's state between them.

    Args:
        apply: ``apply(event)`` applies one event to the estimator's live state and returns
            what the estimator returns for it (e.g. whether a fix passed the gate).
        save: a copy of the live state (the history keeps it as it is: a state that later
            events change in place must be copied).
        restore: ``restore(state)`` makes a saved state the live one (copying it if the
            estimator changes it in place).
        clock: a callable returning the estimator's time, s, after the events applied so far
            (-inf before any; not nan): an event's time in the history is the clock just after
            it is applied, and a checkpoint's time the clock when it is taken.
        checkpoint_every_s: None: a checkpoint before every event (cheap states, e.g.
            immutable tuples). A time, s: a checkpoint before an event once the clock has
            moved at least this far since the last one (the replay cost of a late event: up
            to this much of events).
        keep_s: None: the caller prunes (:meth:`prune`). A time, s: after each new checkpoint,
            the history older than ``clock - keep_s`` is pruned (inclusively).

    Raises:
        ValueError: a ``checkpoint_every_s`` or ``keep_s`` that is not positive.
    """

    def __init__(self, apply: Callable[[E], Any], save: Callable[[], S], restore: Callable[[S], None],
                 clock: Callable[[], float], *, checkpoint_every_s: float | None = None,
                 keep_s: float | None = None) -> None:
        if checkpoint_every_s is not None and not checkpoint_every_s > 0.0:
            raise ValueError(f"checkpoint_every_s must be > 0 or None, got {checkpoint_every_s}")
        if keep_s is not None and not keep_s > 0.0:
            raise ValueError(f"keep_s must be > 0 or None, got {keep_s}")
        self._apply, self._save, self._restore, self._clock = apply, save, restore, clock
        self.checkpoint_every_s = checkpoint_every_s
        self.keep_s = keep_s
        self._events: list[E] = []
        self._times: list[float] = []  # the clock just after each event
        # (index of the event it precedes, clock then, state): one at index 0 at least
        self._checkpoints: list[tuple[int, float, S]] = [(0, clock(), save())]

    # ------------------------------------------------------------------ reading
    @property
    def events(self) -> Sequence[E]:
        """The events kept, in time order (the oldest pruned away)."""
        return self._events

    @property
    def oldest(self) -> tuple[float, S]:
        """``(time s, state)`` of the oldest checkpoint: the state before the events kept;
        an event older than that time cannot be applied."""
        _, t_s, state = self._checkpoints[0]
        return t_s, state

    # ------------------------------------------------------------------ events
    def append(self, event: E) -> Any:
        """Apply ``event`` as the newest and keep it; returns what ``apply`` returned."""
        return self._run(event)

    def insert(self, event: E, t_s: float) -> Any:
        """Apply ``event`` at time ``t_s`` among the events kept: after every event whose
        time is at most ``t_s``, the later ones replayed after it. The newest (``t_s`` at or
        after the clock) is simply applied. Returns what ``apply`` returned for ``event``.

        ``t_s`` only places the event; ``apply`` is not given it, so the event carries its own
        time and applying it must bring the clock to ``t_s`` (as a measurement at ``t_s``
        does: the filter predicts to it first), else the history's order is not the clock's.

        Raises:
            ValueError: ``t_s`` older than :attr:`oldest` (pruned history) or not finite.
        """
        if not math.isfinite(t_s):
            raise ValueError(f"event time must be finite, got {t_s}")
        if t_s >= self._clock():
            return self._run(event)
        i = bisect.bisect_right(self._times, t_s)
        c = bisect.bisect_right([idx for idx, _, _ in self._checkpoints], i) - 1
        k, t_ck, state = self._checkpoints[c]
        if t_ck > t_s:
            raise ValueError(f"event at {t_s} s is older than the kept history (from {t_ck} s)")
        self._restore(state)
        del self._checkpoints[c + 1:]
        tail = self._events[k:]
        del self._events[k:], self._times[k:]
        for old in tail[: i - k]:
            self._run(old)
        out = self._run(event)
        for old in tail[i - k:]:
            self._run(old)
        return out

    def prune(self, before_s: float, *, inclusive: bool = False) -> None:
        """Forget the events before the last checkpoint older than ``before_s`` (at or
        before it with ``inclusive``): that checkpoint becomes :attr:`oldest`."""
        times = [t for _, t, _ in self._checkpoints]
        c = (bisect.bisect_right(times, before_s) if inclusive else bisect.bisect_left(times, before_s)) - 1
        if c <= 0:
            return
        k = self._checkpoints[c][0]
        del self._events[:k], self._times[:k]
        self._checkpoints = [(idx - k, t, s) for idx, t, s in self._checkpoints[c:]]

    # ------------------------------------------------------------------ internals
    def _run(self, event: E) -> Any:
        j = len(self._events)
        last_idx, last_t, _ = self._checkpoints[-1]
        if last_idx < j and (self.checkpoint_every_s is None or self._clock() - last_t >= self.checkpoint_every_s):
            self._checkpoints.append((j, self._clock(), self._save()))
            if self.keep_s is not None:
                self.prune(self._clock() - self.keep_s, inclusive=True)
                j = len(self._events)
        self._events.append(event)  # kept before it is applied: apply may read the history
        out = self._apply(event)
        self._times.append(self._clock())
        return out
