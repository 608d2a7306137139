"""Wall time per stage of the closed loop, measured where the stages run.

The mission loop wraps each stage (physics, each sensor, navigation filter, perception,
guidance, control, observers) in ``timer.stage(name)``. Stages nest; each keeps only its
own (exclusive) time, so a sensor fired inside the physics loop is not counted twice. The
default :data:`NULL_TIMER` does nothing, at the cost of one no-op context manager per stage.
"""

from __future__ import annotations

import time
from collections import defaultdict
from contextlib import AbstractContextManager, nullcontext


class StageTimer:
    """Accumulates exclusive wall time (s) per stage name."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = defaultdict(float)
        self.calls: dict[str, int] = defaultdict(int)
        self._stack: list[str] = []
        self._since = 0.0

    def stage(self, name: str) -> AbstractContextManager[None]:
        """Context manager timing ``name`` (the enclosing stage pauses meanwhile)."""
        return _Stage(self, name)

    def _enter(self, name: str) -> None:
        now = time.perf_counter()
        if self._stack:
            self.seconds[self._stack[-1]] += now - self._since
        self._stack.append(name)
        self.calls[name] += 1
        self._since = now

    def _exit(self) -> None:
        now = time.perf_counter()
        self.seconds[self._stack.pop()] += now - self._since
        self._since = now

    def reset(self) -> None:
        """Forget all totals."""
        self.seconds.clear()
        self.calls.clear()


class _Stage:
    __slots__ = ("_timer", "_name")

    def __init__(self, timer: StageTimer, name: str) -> None:
        self._timer, self._name = timer, name

    def __enter__(self) -> None:
        self._timer._enter(self._name)

    def __exit__(self, *exc: object) -> None:
        self._timer._exit()


class _NullTimer:
    """A timer that times nothing (the default in the mission loop)."""

    _context = nullcontext()

    def stage(self, name: str) -> AbstractContextManager[None]:
        return self._context


NULL_TIMER = _NullTimer()
