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
        self._bar = None
        self._next_pct = self.line_every_pct
        self._shown_s = 0.0
        self._wall0 = time.perf_counter()

    def start(self) -> None:
        if not self.enabled:
            return
        self._wall0 = time.perf_counter()
        if self._tty:
            from tqdm import tqdm

            self._bar = tqdm(total=round(self.planned_s), unit="sim s", desc=self.label, mininterval=0.5,
                             file=self.stream,
                             bar_format="{l_bar}{bar}| {n:.0f}/{total:.0f} sim s [{elapsed}<{remaining}]")

    def update(self, t_s: float, mode: str = "") -> None:
        """Report simulated time ``t_s`` (s) and the mission mode."""
        if not self.enabled:
            return
        if self._bar is not None:
            if t_s - self._shown_s >= 1.0:
                if t_s > self._bar.total:
                    self._bar.total = round(t_s)
                self._bar.update(t_s - self._shown_s)
                self._bar.set_postfix_str(mode, refresh=False)
                self._shown_s = t_s
            return
        pct = 100.0 * t_s / self.planned_s
        if pct >= self._next_pct:
            wall = time.perf_counter() - self._wall0
            rtf = f", {t_s / wall:.1f}x real time" if wall > 0 else ""
            print(f"{self.label}: {min(pct, 999):.0f}% of the planned {self.planned_s:.0f} sim s "
                  f"({t_s:.0f} s, {mode}{rtf})", file=self.stream, flush=True)
            while self._next_pct <= pct:
                self._next_pct += self.line_every_pct

    def close(self, t_s: float) -> None:
        """End the display at simulated time ``t_s``; the bar ends full when the mission ended."""
        if self._bar is not None:
            self._bar.total = round(t_s)
            self._bar.update(t_s - self._shown_s)
            self._bar.close()
            self._bar = None
