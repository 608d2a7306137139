"""Multi-rate sensor scheduling with latency.

Sensors fire at their own rate on the physics clock; each message is delivered to the
autonomy its latency later, in order of delivery time (ties: in the order pushed). A latency
is a fixed number of seconds or a function of the message (an acoustic fix is late by its
travel time). Sensors keep no clocks: the scheduler owns timing.

Besides sensors, the scheduler orders every other periodic event of the mission (the extra
vehicles' sensors and autonomy, the acoustic link: :mod:`sim.features.sea_trial`): a channel
may be tied to a coarser clock (``quantum_s``, the autonomy period), its n-th firing then at
the first tick of that clock at or after its due time ([drake]'s periodic events, each
declared by its component). Each channel belongs to a phase of the mission loop's period
(:data:`PHYSICS`: taken between the physics steps; :data:`AUTONOMY`: taken once the period's
messages are delivered, by the onboard side), and :meth:`SensorScheduler.take_due` takes one
phase's firings.

Firing times are exact: the n-th firing of a channel (n = 0, 1, ...) is at
``first_fire_s + n / rate_hz``, computed from the count (no accumulated floating step, so no
drift over a long run), and no firing is skipped: a sensor faster than the physics step fires
several times in one step, each firing at its own time (:meth:`SensorScheduler.take_due`
gives them in time order; the mission loop moves the true state to each of these times,
:func:`sim.dynamics.truth.interpolate_truth`).
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

Latency = float | Callable[[Any], float]
#: Rounding absorbed when a due time is moved to a channel's clock ticks, s.
QUANTUM_TOL_S = 1e-9
#: Phases of the loop's period: firings taken between the physics steps (sensors, the extra
#: vehicles) and firings taken after the period's messages are delivered (the acoustic link).
PHYSICS, AUTONOMY = "physics", "autonomy"
PHASES = (PHYSICS, AUTONOMY)


@dataclass
class _Channel:
    name: str
    order: int  # position in the table: breaks ties between channels firing at the same time
    rate_hz: float
    latency_s: Callable[[Any], float]
    first_fire_s: float
    n_fired: int = 0
    quantum_s: float | None = None
    phase: str = PHYSICS
    offset_s: float = 0.0  # first firing this long after a reset

    @property
    def next_fire_s(self) -> float:
        due = self.first_fire_s + self.n_fired / self.rate_hz
        if self.quantum_s is None:
            return due
        # the first tick k * quantum at or after the due time (a nanosecond of rounding absorbed)
        return math.ceil((due - QUANTUM_TOL_S) / self.quantum_s) * self.quantum_s


class SensorScheduler:
    """Tracks when each named sensor is due and queues messages until delivery.

    Args:
        eps_s: tolerance when comparing clocks, s: a firing or delivery at most ``eps_s``
            after the time asked is due then (the mission uses a millionth of the physics
            step: only rounding of exact times is absorbed).
    """

    def __init__(self, eps_s: float = 1e-9) -> None:
        self.eps_s = eps_s
        self._channels: dict[str, _Channel] = {}
        self._next_s = dict.fromkeys(PHASES, math.inf)  # earliest next firing of any channel, per phase
        self._by_phase: dict[str, list[_Channel]] = {p: [] for p in PHASES}  # in table order
        # (deliver_s, seq, name, message): ordered by time, then push order (seq is unique)
        self._queue: list[tuple[float, int, str, Any]] = []
        self._seq = 0

    def add(self, name: str, rate_hz: float, latency_s: Latency = 0.0, first_fire_s: float = 0.0,
            quantum_s: float | None = None, *, phase: str = PHYSICS, offset_s: float = 0.0) -> None:
        """Add a channel firing every ``1 / rate_hz`` s from ``first_fire_s``.

        Args:
            name: channel (sensor or event) name.
            rate_hz: firing rate, Hz.
            latency_s: delay from firing to delivery, s, or a function of the message
                giving it (e.g. ``sensor.latency_s``).
            first_fire_s: time of the first firing, s (before ``offset_s``).
            quantum_s: None: fire at the exact times. A period, s: each firing moves to the
                first multiple of it at or after its due time (an event run at the autonomy
                ticks); ``rate_hz`` must not exceed ``1 / quantum_s``.
            phase: :data:`PHYSICS` or :data:`AUTONOMY`, the part of the loop's period whose
                :meth:`take_due` takes the channel's firings.
            offset_s: after a :meth:`reset` to ``t``, the first firing is at ``t + offset_s``
                (an event that has nothing to do at the start: one period).

        Raises:
            ValueError: a rate that is not positive and finite, a negative fixed latency, a
                quantum that is not positive or one shorter than the channel's period, an
                unknown phase or a negative offset.
        """
        if phase not in PHASES:
            raise ValueError(f"channel {name!r}: phase must be one of {PHASES}, got {phase!r}")
        if not offset_s >= 0.0:
            raise ValueError(f"channel {name!r}: offset_s must be >= 0, got {offset_s}")
        if not rate_hz > 0.0 or not math.isfinite(rate_hz):
            raise ValueError(f"sensor {name!r}: rate_hz must be > 0, got {rate_hz}")
        if callable(latency_s):
            latency = latency_s
        else:
            fixed = float(latency_s)
            if not fixed >= 0.0:
                raise ValueError(f"sensor {name!r}: latency_s must be >= 0, got {latency_s}")
            latency = lambda _msg, _fixed=fixed: _fixed  # noqa: E731
        if quantum_s is not None and not (quantum_s > 0.0 and rate_hz * quantum_s <= 1.0 + 1e-9):
            raise ValueError(f"channel {name!r}: quantum_s must be > 0 and at most the period "
                             f"1 / rate_hz = {1.0 / rate_hz:g} s, got {quantum_s}")
        order = self._channels[name].order if name in self._channels else len(self._channels)
        self._channels[name] = _Channel(name, order, float(rate_hz), latency, float(first_fire_s) + float(offset_s),
                                        quantum_s=None if quantum_s is None else float(quantum_s),
                                        phase=phase, offset_s=float(offset_s))
        self._by_phase = {p: [ch for ch in self._channels.values() if ch.phase == p] for p in PHASES}
        self._update_next(phase)

    def _update_next(self, phase: str) -> None:
        self._next_s[phase] = min((ch.next_fire_s for ch in self._by_phase[phase]), default=math.inf)

    def reset(self, t_s: float = 0.0) -> None:
        """Empty the queue; every channel fires next (its firing 0) at ``t_s``."""
        self._queue.clear()
        self._seq = 0
        for ch in self._channels.values():
            ch.first_fire_s = float(t_s) + ch.offset_s
            ch.n_fired = 0
        for phase in PHASES:
            self._update_next(phase)

    @property
    def next_fire_s(self) -> float:
        """Time of the earliest :data:`PHYSICS` firing not yet taken, s (inf without one)."""
        return self._next_s[PHYSICS]

    def take_due(self, t_s: float, phase: str = PHYSICS) -> list[tuple[float, str]]:
        """Every firing of ``phase`` at or before ``t_s`` not yet taken, as ``(firing time s,
        name)`` in time order (ties: in the order the channels were added); each channel's
        clock advances past them. A channel faster than the interval since the last call
        fires once per period in it (no firing is skipped)."""
        limit = t_s + self.eps_s
        if self._next_s[phase] > limit:  # most physics steps: nothing due
            return []
        out = []
        nxt = math.inf
        for ch in self._by_phase[phase]:
            t_fire = ch.next_fire_s
            while t_fire <= limit:
                out.append((t_fire, ch.order, ch.name))
                ch.n_fired += 1
                t_fire = ch.next_fire_s
            if t_fire < nxt:
                nxt = t_fire
        self._next_s[phase] = nxt
        out.sort()
        return [(t, name) for t, _, name in out]

    def due(self, t_s: float) -> list[str]:
        """Names of the firings at or before ``t_s`` not yet taken, in time order (a channel
        appears once per firing); see :meth:`take_due`, which also gives the times."""
        return [name for _, name in self.take_due(t_s)]

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
