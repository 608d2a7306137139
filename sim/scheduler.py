"""Multi-rate sensor scheduling with latency.

Sensors fire at their own rate on the physics clock; each message is delivered to the
autonomy its latency later, in order of delivery time (ties: in the order pushed). A latency
is a fixed number of seconds or a function of the message (an acoustic fix is late by its
travel time). Sensors keep no clocks: the scheduler owns timing.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

Latency = float | Callable[[Any], float]


@dataclass
class _Channel:
    name: str
    period_s: float
    latency_s: Callable[[Any], float]
    next_fire_s: float


class SensorScheduler:
    """Tracks when each named sensor is due and queues messages until delivery.

    Args:
        eps_s: tolerance when comparing clocks (a fraction of the physics step).
    """

    def __init__(self, eps_s: float = 1e-9) -> None:
        self.eps_s = eps_s
        self._channels: dict[str, _Channel] = {}
        self._next_any_s = math.inf  # earliest next_fire_s of any channel
        # (deliver_s, seq, name, message): ordered by time, then push order (seq is unique)
        self._queue: list[tuple[float, int, str, Any]] = []
        self._seq = 0

    def add(self, name: str, rate_hz: float, latency_s: Latency = 0.0, first_fire_s: float = 0.0) -> None:
        """Add a channel firing every ``1 / rate_hz`` s from ``first_fire_s``.

        Args:
            name: channel (sensor) name.
            rate_hz: firing rate, Hz.
            latency_s: delay from firing to delivery, s, or a function of the message
                giving it (e.g. ``sensor.latency_s``).
            first_fire_s: time of the first firing, s.

        Raises:
            ValueError: a rate that is not positive and finite, or a negative fixed latency.
        """
        if not rate_hz > 0.0 or not math.isfinite(rate_hz):
            raise ValueError(f"sensor {name!r}: rate_hz must be > 0, got {rate_hz}")
        if callable(latency_s):
            latency = latency_s
        else:
            fixed = float(latency_s)
            if not fixed >= 0.0:
                raise ValueError(f"sensor {name!r}: latency_s must be >= 0, got {latency_s}")
            latency = lambda _msg, _fixed=fixed: _fixed  # noqa: E731
        self._channels[name] = _Channel(name, 1.0 / rate_hz, latency, first_fire_s)
        self._next_any_s = min(ch.next_fire_s for ch in self._channels.values())

    def reset(self, t_s: float = 0.0) -> None:
        self._queue.clear()
        self._seq = 0
        for ch in self._channels.values():
            ch.next_fire_s = t_s
        self._next_any_s = t_s

    def due(self, t_s: float) -> list[str]:
        """Names of the sensors that fire at time ``t_s`` (each advances its clock)."""
        if self._next_any_s > t_s + self.eps_s:  # most physics steps: nothing due
            return []
        out = []
        for ch in self._channels.values():
            if ch.next_fire_s <= t_s + self.eps_s:
                out.append(ch.name)
                # Catch up without bursts if a sensor was starved.
                ch.next_fire_s += ch.period_s * max(1, math.floor((t_s - ch.next_fire_s) / ch.period_s + 1e-9) + 1)
        self._next_any_s = min((ch.next_fire_s for ch in self._channels.values()), default=math.inf)
        return out

    def push(self, name: str, t_s: float, message: Any) -> None:
        """Queue ``message`` sampled at ``t_s`` for delivery after the channel's latency.

        Raises:
            ValueError: the latency of this message is negative or not finite.
        """
        ch = self._channels[name]
        latency = ch.latency_s(message)
        if not (latency >= 0.0 and math.isfinite(latency)):
            raise ValueError(f"sensor {name!r}: latency of a message must be finite and >= 0, got {latency}")
        heapq.heappush(self._queue, (t_s + latency, self._seq, name, message))
        self._seq += 1

    def pop_ready(self, t_s: float) -> list[tuple[str, Any]]:
        """Messages whose delivery time has come, oldest first."""
        out = []
        queue, limit = self._queue, t_s + self.eps_s
        while queue and queue[0][0] <= limit:
            _, _, name, message = heapq.heappop(queue)
            out.append((name, message))
        return out
