"""Multi-rate sensor scheduling with latency.

Sensors fire at their own rate on the physics clock; each message is delivered to the
autonomy ``latency_s`` later, in order of delivery time. Sensors keep no clocks: the
scheduler owns timing.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass, field
from typing import Any


@dataclass
class _Channel:
    name: str
    period_s: float
    latency_s: float
    next_fire_s: float


@dataclass(order=True)
class _Pending:
    deliver_s: float
    seq: int
    name: str = field(compare=False)
    message: Any = field(compare=False)


class SensorScheduler:
    """Tracks when each named sensor is due and queues messages until delivery.

    Args:
        eps_s: tolerance when comparing clocks (a fraction of the physics step).
    """

    def __init__(self, eps_s: float = 1e-9) -> None:
        self.eps_s = eps_s
        self._channels: dict[str, _Channel] = {}
        self._queue: list[_Pending] = []
        self._seq = 0

    def add(self, name: str, rate_hz: float, latency_s: float = 0.0, first_fire_s: float = 0.0) -> None:
        if not rate_hz > 0.0 or not math.isfinite(rate_hz):
            raise ValueError(f"sensor {name!r}: rate_hz must be > 0, got {rate_hz}")
        if latency_s < 0.0:
            raise ValueError(f"sensor {name!r}: latency_s must be >= 0, got {latency_s}")
        self._channels[name] = _Channel(name, 1.0 / rate_hz, latency_s, first_fire_s)

    def reset(self, t_s: float = 0.0) -> None:
        self._queue.clear()
        self._seq = 0
        for ch in self._channels.values():
            ch.next_fire_s = t_s

    def due(self, t_s: float) -> list[str]:
        """Names of the sensors that fire at time ``t_s`` (each advances its clock)."""
        out = []
        for ch in self._channels.values():
            if ch.next_fire_s <= t_s + self.eps_s:
                out.append(ch.name)
                # Catch up without bursts if a sensor was starved.
                ch.next_fire_s += ch.period_s * max(1, math.floor((t_s - ch.next_fire_s) / ch.period_s + 1e-9) + 1)
        return out

    def push(self, name: str, t_s: float, message: Any) -> None:
        ch = self._channels[name]
        heapq.heappush(self._queue, _Pending(t_s + ch.latency_s, self._seq, name, message))
        self._seq += 1

    def pop_ready(self, t_s: float) -> list[tuple[str, Any]]:
        """Messages whose delivery time has come, oldest first."""
        out = []
        while self._queue and self._queue[0].deliver_s <= t_s + self.eps_s:
            p = heapq.heappop(self._queue)
            out.append((p.name, p.message))
        return out
