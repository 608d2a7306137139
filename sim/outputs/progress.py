"""Progress of a mission on the console: a bar on a terminal, a line every few percent otherwise."""

from __future__ import annotations

import sys
import time
from typing import TextIO


class MissionProgress:
    """Shows how far a mission is through its planned length of simulated time.

    Args:
        label: shown at the start of each line (the scenario name).
        planned_s: the planned mission length, s of simulated time (the bar's 100 %).
        stream: where to write (default stderr).
        line_every_pct: without a terminal, one line each time this many percent pass.
        enabled: False shows nothing.
    """

    def __init__(self, label: str, planned_s: float, stream: TextIO | None = None,
                 line_every_pct: float = 10.0, enabled: bool = True) -> None:
        self.label = label
        self.planned_s = max(float(planned_s), 1e-9)
        self.stream = stream if stream is not None else sys.stderr
        self.line_every_pct = float(line_every_pct)
        self.enabled = enabled
        self._tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self._next_pct = self.line_every_pct
        self._last_draw = -1.0
        self._wall0 = time.perf_counter()

    def start(self) -> None:
        if not self.enabled:
            return
        self._wall0 = time.perf_counter()
        self._last_draw = -1.0

    def _line(self, t_s: float, mode: str) -> str:
        pct = 100.0 * t_s / self.planned_s
        wall = time.perf_counter() - self._wall0
        rtf = f", {t_s / wall:.1f}x real time" if wall > 0 else ""
        return (f"{self.label}: {min(pct, 999):3.0f}% of the planned {self.planned_s:.0f} sim s "
                f"({t_s:.0f} s, {mode}{rtf})")

    def update(self, t_s: float, mode: str = "") -> None:
        """Report simulated time ``t_s`` (s) and the mission mode."""
        if not self.enabled:
            return
        if self._tty:  # redraw one line in place, at most twice a second
            now = time.perf_counter()
            if now - self._last_draw >= 0.5:
                self._last_draw = now
                self._write("\r\x1b[K" + self._line(t_s, mode))
            return
        pct = 100.0 * t_s / self.planned_s
        if pct >= self._next_pct:
            self._write(self._line(t_s, mode) + "\n")
            while self._next_pct <= pct:
                self._next_pct += self.line_every_pct

    def close(self, t_s: float, mode: str = "end") -> None:
        """End the display at simulated time ``t_s``."""
        if self.enabled and self._tty:
            self._write("\r\x1b[K" + self._line(t_s, mode) + "\n")

    def _write(self, text: str) -> None:
        try:
            self.stream.write(text)
            self.stream.flush()
        except (BrokenPipeError, ValueError):
            self.enabled = False
