"""Time-division access to a half-duplex acoustic link shared by an AUV and a surface vehicle.

Each cycle of ``cycle_s`` starts with the surface vehicle's slot of ``surface_slot_s`` (its
USBL fix of the AUV goes down); the AUV talks in the rest of the cycle (its detections go
up). A node hands a packet to its modem only if the packet's duration, its travel time to
the receiver (range / sound speed, plus the longest multipath delay) and a guard end inside
the node's own slot, so the packet has arrived before the receiver's own slot opens and the
two modems never transmit into each other's reception (a half-duplex modem loses what
arrives while it talks). A slot of ``L`` s therefore carries a packet of ``d`` s only to
ranges up to ``c * (L - d - guard_s - multipath delay)`` (:meth:`TdmaSchedule.reach_m`);
beyond it the packet waits. Both vehicles keep the schedule from the shared mission clock
(GNSS time on the surface, the AUV's clock set at the surface before the dive).

:class:`SlotSender` is one node's application queue in front of its modem: it releases one
packet at a time, when it fits in the node's slot and the previous one has left.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

SURFACE, AUV = "surface", "auv"
_EPS_S = 1e-9


@dataclass(frozen=True, slots=True)
class TdmaSchedule:
    """The two-slot cycle.

    Attributes:
        cycle_s: cycle length, s.
        surface_slot_s: the surface vehicle's slot at the start of each cycle, s.
        guard_s: margin after a packet's arrival before the slot ends, s (covers the error
            of the sender's range estimate and the motion while the packet travels: 0.05 s
            is 75 m at 1500 m/s).
    """

    cycle_s: float
    surface_slot_s: float
    guard_s: float

    def __post_init__(self) -> None:
        if not (0.0 < self.surface_slot_s < self.cycle_s and self.guard_s >= 0.0):
            raise ValueError(f"TdmaSchedule needs 0 < surface_slot_s < cycle_s and guard_s >= 0, got "
                             f"{self.surface_slot_s}, {self.cycle_s}, {self.guard_s}")

    def slot_end_s(self, node: str, t_s: float) -> float:
        """End of ``node``'s slot containing ``t_s`` (s), or -inf when ``t_s`` is outside its slots."""
        # a tick meant to fall on a slot's start may land a rounding error before it
        start = math.floor((t_s + _EPS_S) / self.cycle_s) * self.cycle_s
        phase = max(t_s - start, 0.0)
        if node == SURFACE:
            return start + self.surface_slot_s if phase < self.surface_slot_s else -math.inf
        if node == AUV:
            return start + self.cycle_s if phase >= self.surface_slot_s else -math.inf
        raise ValueError(f"TdmaSchedule: node must be {SURFACE!r} or {AUV!r}, got {node!r}")

    def slot_length_s(self, node: str) -> float:
        """Length of ``node``'s slot, s."""
        self.slot_end_s(node, 0.0)  # checks the node name
        return self.surface_slot_s if node == SURFACE else self.cycle_s - self.surface_slot_s

    def fits(self, node: str, t_s: float, duration_s: float, travel_s: float) -> bool:
        """A packet of ``duration_s`` started at ``t_s`` by ``node`` has arrived, ``travel_s``
        later (range / sound speed plus the longest multipath delay, s), with ``guard_s`` to
        spare, before that node's slot ends.

        Raises:
            ValueError: ``travel_s`` negative or not finite, or an unknown node.
        """
        if not (math.isfinite(travel_s) and travel_s >= 0.0):
            raise ValueError(f"TdmaSchedule.fits: travel_s must be finite and >= 0, got {travel_s}")
        return t_s + duration_s + travel_s + self.guard_s <= self.slot_end_s(node, t_s)

    def reach_m(self, node: str, duration_s: float, sound_speed_mps: float, multipath_max_delay_s: float) -> float:
        """Farthest range (m) to which ``node``'s slot carries a packet of ``duration_s`` sent
        at the slot's start: ``c * (slot - duration - guard - multipath delay)``; negative when
        the slot cannot hold it at any range."""
        return sound_speed_mps * (self.slot_length_s(node) - duration_s - self.guard_s - multipath_max_delay_s)


class SlotSender:
    """One node's queue of packets waiting for its slot.

    Args:
        schedule: the cycle.
        node: ``"surface"`` or ``"auv"``.
        max_age_s: packets queued longer than this are dropped unsent (stale news), s.

    Attributes:
        n_dropped_stale: packets dropped for age.
        n_superseded: packets :meth:`replace` dropped unsent (they had not fitted yet).
    """

    def __init__(self, schedule: TdmaSchedule, node: str, max_age_s: float = math.inf) -> None:
        schedule.slot_end_s(node, 0.0)  # checks the node name
        self.schedule, self.node, self.max_age_s = schedule, node, float(max_age_s)
        self._queue: deque[tuple[float, bytes]] = deque()
        self._busy_until_s = -math.inf
        self.n_dropped_stale = 0
        self.n_superseded = 0

    def __len__(self) -> int:
        return len(self._queue)

    def put(self, t_s: float, payload: bytes) -> None:
        """Queue ``payload`` at time ``t_s``."""
        self._queue.append((float(t_s), bytes(payload)))

    def replace(self, t_s: float, payload: bytes) -> None:
        """Keep only ``payload`` queued (the newest fix supersedes an unsent one)."""
        self.n_superseded += len(self._queue)
        self._queue.clear()
        self.put(t_s, payload)

    def release(self, t_s: float, duration_s, travel_s: float) -> list[bytes]:
        """Packets to hand to the modem at ``t_s``: while the next one (lasting
        ``duration_s(len(payload))`` s, then ``travel_s`` s to the receiver, multipath
        included) fits in the slot after the ones already released."""
        while self._queue and t_s - self._queue[0][0] > self.max_age_s:
            self._queue.popleft()
            self.n_dropped_stale += 1
        out: list[bytes] = []
        start = max(t_s, self._busy_until_s)
        while self._queue:
            d = duration_s(len(self._queue[0][1]))
            if not self.schedule.fits(self.node, start, d, travel_s) or self.schedule.slot_end_s(self.node, start) != \
                    self.schedule.slot_end_s(self.node, t_s):
                break
            out.append(self._queue.popleft()[1])
            start += d
        if out:
            self._busy_until_s = start
        return out
