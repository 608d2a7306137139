"""A seeded half-duplex acoustic modem channel between named nodes (paper 000 section VII).

Each node (a vehicle's modem) has a FIFO send queue. A node transmits the head of its queue
as soon as its modem is free: not transmitting, and not hearing a packet arrive (carrier
sense: a half-duplex modem cannot send while it receives). A packet of ``n`` payload bytes
occupies ``(n + overhead) * 8 / rate`` seconds; every other node hears it from
``t_start + range / c`` for that long, and the addressee receives it at the end of that
interval (plus a multipath delay when the packet took a longer path). It is lost when

- the channel drops it: a Bernoulli draw with the probability of
  :meth:`scenarios.config.comms.AcousticLinkConfig.delivery_prob` (logistic in range, plus
  each end's self-noise under way), cause ``"channel"``;
- the addressee transmits during any part of its arrival (half duplex), ``"half_duplex"``;
- another packet's signal overlaps it at the addressee, ``"collision"``;
- the sender's queue is full when it is sent, ``"queue_full"``.

Timing is exact in continuous time: the event loop in :meth:`AcousticLink.advance` starts
transmissions at their exact times, however coarse the caller's ticks. Each transmission
draws three uniforms (loss, multipath, multipath delay) from the link's own generator, in
the order transmissions start, so a run is reproducible from the root seed.

Moving nodes: positions are linearly interpolated between the two latest
:meth:`AcousticLink.advance` calls, and the range is taken at the start of transmission;
the receiver's motion during the travel time (``range / c``) is neglected, an arrival-time
error of at most ``v_rel * range / c^2`` (44 us at 1 m/s relative speed and 100 m). Every
node hears every transmission, however far (carrier sense and collisions ignore range).

Driving it from the mission loop, each autonomy tick ``t``::

    link = AcousticLink.from_config(scenario.comms.acoustic, ["auv", "buoy"], seed=scenario.seed)
    ...
    link.advance(t, {"auv": auv_pos_ned, "buoy": buoy_pos_ned})      # channel events up to t
    for pkt in link.delivered(t, dst="buoy"):                          # arrived by t
        report = decode(pkt.payload)          # autonomy.comms.messages.DetectionReport
        surface_world_model.update(...)       # report.to_localized(origin, epoch, class_names)
    for pkt in link.delivered(t, dst="auv"):
        fix = decode(pkt.payload)             # UsblFixReport, pkt.latency_s late
    for det in new_detections:                # sent now, on the air when the modem is free
        link.send(t, "auv", "buoy", DetectionReport.from_localized(det, ...).encode())
    ...
    link.stats()                              # sent, delivered, lost, mean / p95 latency
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from scenarios.config.comms import AcousticLinkConfig
from sim.rng import component_rng

OUTCOMES = ("delivered", "channel", "half_duplex", "collision", "queue_full")
_INF = math.inf
#: Intervals overlapping by less than this (s) do not: back-to-back packets of one sender
#: meet exactly, up to floating-point rounding of the summed times.
_EPS_S = 1e-9


@dataclass(frozen=True, slots=True)
class Packet:
    """A packet whose fate is known.

    Attributes:
        id: the id :meth:`AcousticLink.send` returned.
        src, dst: sending and addressed node.
        payload: the bytes sent.
        t_send_s: when it was handed to the sender's modem, s.
        t_tx_start_s: when its transmission began, s (NaN: never sent, queue full).
        t_arrival_s: when its last bit reached ``dst`` (the delivery time), s (NaN: never sent).
        range_m: sender-receiver range at the start of transmission, m (NaN: never sent).
        multipath: it arrived by a longer path (extra delay).
        outcome: ``"delivered"`` or the cause of loss (:data:`OUTCOMES`).
    """

    id: int
    src: str
    dst: str
    payload: bytes
    t_send_s: float
    t_tx_start_s: float
    t_arrival_s: float
    range_m: float
    multipath: bool
    outcome: str

    @property
    def latency_s(self) -> float:
        """Send-to-delivery delay (queueing + duration + travel + multipath), s."""
        return self.t_arrival_s - self.t_send_s


@dataclass(frozen=True, slots=True)
class LinkStats:
    """Counts and latency of the packets of one direction (or all).

    ``sent = delivered + lost + pending``; ``lost`` sums the four causes. Latencies (s) are
    over delivered packets (NaN when none).
    """

    sent: int
    delivered: int
    lost: int
    lost_channel: int
    lost_half_duplex: int
    lost_collision: int
    dropped_queue_full: int
    pending: int
    mean_latency_s: float
    p95_latency_s: float

    def to_dict(self) -> dict[str, float]:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def _position(name: str, value: ArrayLike) -> tuple[float, float, float]:
    """A finite (3,) position as a tuple of floats (plain Python: this runs every tick)."""
    try:
        x, y, z = (float(v) for v in (value.tolist() if isinstance(value, np.ndarray) else value))
    except (TypeError, ValueError):
        x = y = z = math.nan
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
        raise ValueError(f"acoustic link: position of {name!r} must be a finite (3,) NED vector, got {value!r}")
    return x, y, z


def _overlap(a0: float, a1: float, b0: float, b1: float) -> bool:
    """[a0, a1) and [b0, b1) share more than :data:`_EPS_S`."""
    return min(a1, b1) - max(a0, b0) > _EPS_S


class _Flight:
    """A transmitted packet until its arrival ends at the addressee."""

    __slots__ = ("id", "src", "dst", "payload", "t_send", "t_tx", "a0", "a1", "range_m", "multipath", "lost")

    def __init__(self, pid: int, src: str, dst: str, payload: bytes, t_send: float) -> None:
        self.id, self.src, self.dst, self.payload, self.t_send = pid, src, dst, payload, t_send
        self.t_tx = self.a0 = self.a1 = self.range_m = math.nan
        self.multipath = False
        self.lost: str | None = None

    def record(self) -> Packet:
        return Packet(self.id, self.src, self.dst, self.payload, self.t_send, self.t_tx, self.a1, self.range_m,
                      self.multipath, self.lost or "delivered")


class _Node:
    __slots__ = ("name", "queue", "tx_start", "tx_end", "arrivals", "pos_prev", "pos", "speed", "inbox")

    def __init__(self, name: str) -> None:
        self.name = name
        self.queue: deque[_Flight] = deque()
        self.tx_start = self.tx_end = -_INF
        self.arrivals: list[tuple[float, float, _Flight]] = []  # (start, end, packet) of signals it hears
        self.pos_prev: tuple[float, float, float] | None = None
        self.pos: tuple[float, float, float] | None = None
        self.speed = 0.0
        self.inbox: deque[Packet] = deque()  # delivered, by arrival time, not yet collected


class AcousticLink:
    """Half-duplex acoustic modems between named nodes.

    Args:
        cfg: channel parameters (:class:`scenarios.config.comms.AcousticLinkConfig`).
        nodes: node names (two or more, distinct).
        rng: the link's own generator (``sim.rng.component_rng(seed, "acoustic_link")``).

    Raises:
        ValueError: fewer than two nodes, or a repeated name.
    """

    def __init__(self, cfg: AcousticLinkConfig, nodes: Sequence[str], rng: np.random.Generator) -> None:
        names = list(nodes)
        if len(names) < 2 or len(set(names)) != len(names):
            raise ValueError(f"acoustic link: needs two or more distinct node names, got {names}")
        self.cfg = cfg
        self._rng = rng
        self._nodes = {n: _Node(n) for n in names}
        self._t_prev = -_INF  # time of the latest positions (node.pos)
        self._interp_from = -_INF  # time of the positions before them (node.pos_prev)
        self._t = -_INF  # channel events are settled up to here
        self._next_id = 0
        self._in_flight: list[_Flight] = []
        self._done: list[Packet] = []

    @classmethod
    def from_config(cls, cfg: AcousticLinkConfig, nodes: Sequence[str], seed: int) -> "AcousticLink":
        """The link of ``nodes`` with its generator ``component_rng(seed, "acoustic_link")``."""
        return cls(cfg, nodes, component_rng(seed, "acoustic_link"))

    @property
    def nodes(self) -> tuple[str, ...]:
        return tuple(self._nodes)

    @property
    def time_s(self) -> float:
        """Time up to which channel events are settled (the last :meth:`advance`), s."""
        return self._t

    # ------------------------------------------------------------------ API
    def send(self, t_s: float, src: str, dst: str, payload: bytes) -> int:
        """Queue ``payload`` at ``src``'s modem for ``dst`` at time ``t_s``; its id.

        A full queue drops the packet (outcome ``"queue_full"``); the id is returned anyway.

        Raises:
            ValueError: unknown or equal nodes, an empty or too long payload, or ``t_s``
                earlier than the last :meth:`advance`.
        """
        node = self._node(src)
        self._node(dst)
        if src == dst:
            raise ValueError(f"acoustic link: {src!r} cannot send to itself")
        payload = bytes(payload)
        if not 1 <= len(payload) <= self.cfg.max_payload_bytes:
            raise ValueError(f"acoustic link: payload of {len(payload)} bytes; allowed 1 to "
                             f"{self.cfg.max_payload_bytes} (comms.acoustic.max_payload_bytes)")
        if not t_s >= self._t:
            raise ValueError(f"acoustic link: send at t = {t_s} s, before the last advance ({self._t} s)")
        f = _Flight(self._next_id, src, dst, payload, float(t_s))
        self._next_id += 1
        if len(node.queue) >= self.cfg.queue_limit:
            f.lost = "queue_full"
            self._done.append(f.record())
        else:
            node.queue.append(f)
        return f.id

    def advance(self, t_s: float, positions_ned: Mapping[str, ArrayLike],
                speeds_mps: Mapping[str, float] | None = None) -> None:
        """Run the channel up to ``t_s`` with the nodes at ``positions_ned`` at ``t_s``.

        Args:
            t_s: time, s; not earlier than the previous call.
            positions_ned: node -> (3,) NED position at ``t_s``, m (every node).
            speeds_mps: node -> speed through the water, m/s, for the self-noise loss;
                nodes left out get the speed between the last two calls' positions.

        Raises:
            ValueError: time going back, or a node without a finite (3,) position.
        """
        if not t_s >= self._t:
            raise ValueError(f"acoustic link: advance to t = {t_s} s, before {self._t} s")
        missing = [n for n in self._nodes if n not in positions_ned]
        if missing:
            raise ValueError(f"acoustic link: no position for node {missing[0]!r}")
        new_pos = {name: _position(name, positions_ned[name]) for name in self._nodes}  # all checked first
        dt = t_s - self._t_prev
        for name, node in self._nodes.items():
            pos = new_pos[name]
            node.pos_prev = node.pos if node.pos is not None else pos
            node.pos = pos
            if speeds_mps is not None and name in speeds_mps:
                node.speed = float(speeds_mps[name])
            elif dt > 0.0 and math.isfinite(dt):
                node.speed = math.dist(node.pos_prev, pos) / dt
        t_prev, self._t_prev = self._t_prev, float(t_s)
        self._interp_from = t_prev

        # Events run in time order from the settled time: a start is never earlier than the
        # latest event (the signals that ended before it are forgotten, so a start computed
        # from before it would miss them and fall into what is still arriving).
        t_event = self._t
        while True:
            best, best_t = None, _INF
            for node in self._nodes.values():
                if node.queue:
                    ts = self._earliest_start(node, t_event)
                    if ts < best_t:
                        best, best_t = node, ts
            if best is None or best_t > t_s:
                break
            self._transmit(best, best_t)
            t_event = best_t

        self._t = float(t_s)
        self._settle(t_s)

    def delivered(self, t_s: float, dst: str | None = None) -> list[Packet]:
        """Packets that reached their addressee by ``t_s`` and were not collected yet, by arrival time.

        Args:
            t_s: time, s; not later than the last :meth:`advance`.
            dst: only this node's packets (None: every node's).

        Raises:
            ValueError: ``t_s`` beyond the last :meth:`advance`, or an unknown node.
        """
        if t_s > self._t:
            raise ValueError(f"acoustic link: delivered({t_s}) needs advance() to {t_s} s first (at {self._t} s)")
        nodes = [self._node(dst)] if dst is not None else list(self._nodes.values())
        out: list[Packet] = []
        for node in nodes:
            while node.inbox and node.inbox[0].t_arrival_s <= t_s:
                out.append(node.inbox.popleft())
        out.sort(key=lambda p: (p.t_arrival_s, p.id))
        return out

    def finished(self) -> list[Packet]:
        """Every packet whose fate is known (delivered or lost), in the order it was settled."""
        return list(self._done)

    def stats(self, src: str | None = None, dst: str | None = None) -> LinkStats:
        """Counts and latency of the packets from ``src`` to ``dst`` (None: any)."""
        def keep(s: str, d: str) -> bool:
            return (src is None or s == src) and (dst is None or d == dst)

        counts = dict.fromkeys(OUTCOMES, 0)
        latencies = []
        for p in self._done:
            if keep(p.src, p.dst):
                counts[p.outcome] += 1
                if p.outcome == "delivered":
                    latencies.append(p.latency_s)
        pending = sum(keep(f.src, f.dst) for n in self._nodes.values() for f in n.queue)
        pending += sum(keep(f.src, f.dst) for f in self._in_flight)
        lost = sum(counts[k] for k in OUTCOMES[1:])
        lat = np.asarray(latencies)
        return LinkStats(
            sent=counts["delivered"] + lost + pending, delivered=counts["delivered"], lost=lost,
            lost_channel=counts["channel"], lost_half_duplex=counts["half_duplex"],
            lost_collision=counts["collision"], dropped_queue_full=counts["queue_full"], pending=pending,
            mean_latency_s=float(lat.mean()) if lat.size else math.nan,
            p95_latency_s=float(np.percentile(lat, 95)) if lat.size else math.nan)

    # ------------------------------------------------------------ internals
    def _node(self, name: str) -> _Node:
        try:
            return self._nodes[name]
        except KeyError:
            raise ValueError(f"acoustic link: unknown node {name!r} (known: {list(self._nodes)})") from None

    def _earliest_start(self, node: _Node, t_event: float) -> float:
        """When ``node`` can start its head packet: sent, its last transmission over, not before
        ``t_event`` (the latest channel event: what ended before it is forgotten), and no
        signal arriving at it (carrier sense: it waits for the end of every arrival it hears,
        back-to-back ones included)."""
        ts = max(node.queue[0].t_send, node.tx_end, t_event)
        moved = True
        while moved:
            moved = False
            for a0, a1, _ in node.arrivals:
                # an arrival starting within rounding of ts (the next of back-to-back packets,
                # its start summed along another path) is already arriving
                if a0 - _EPS_S <= ts < a1 - _EPS_S:
                    ts, moved = a1, True
        return ts

    def _pos_at(self, node: _Node, t: float) -> tuple[float, float, float]:
        t0, t1 = self._interp_from, self._t_prev
        p0, p1 = node.pos_prev, node.pos
        if not (t1 > t0 and math.isfinite(t0)) or p0 == p1:
            return p1
        w = min(max((t - t0) / (t1 - t0), 0.0), 1.0)
        return (p0[0] + w * (p1[0] - p0[0]), p0[1] + w * (p1[1] - p0[1]), p0[2] + w * (p1[2] - p0[2]))

    def _transmit(self, node: _Node, ts: float) -> None:
        cfg = self.cfg
        f = node.queue.popleft()
        dur = cfg.packet_duration_s(len(f.payload))
        f.t_tx = ts
        node.tx_start, node.tx_end = ts, ts + dur
        for other in self._nodes.values():  # signals over before ts matter no more (starts never go back)
            if other.arrivals and other.arrivals[0][1] <= ts:
                other.arrivals = [a for a in other.arrivals if a[1] > ts]
        for a0, a1, g in node.arrivals:  # half duplex: deaf to what arrives while it sends
            if g.dst == node.name and g.lost is None and _overlap(a0, a1, ts, ts + dur):
                g.lost = "half_duplex"
        u_loss, u_mp, u_delay = self._rng.random(3).tolist()
        p_src = self._pos_at(node, ts)
        dst = self._nodes[f.dst]
        for other in self._nodes.values():
            if other is node:
                continue
            r = math.dist(p_src, self._pos_at(other, ts))
            a0 = ts + r / cfg.sound_speed_mps
            if other is dst:
                f.range_m = r
                if u_mp < cfg.multipath_prob:
                    f.multipath = True
                    a0 += u_delay * cfg.multipath_max_delay_s
                f.a0, f.a1 = a0, a0 + dur
                p = cfg.delivery_prob(r, node.speed, dst.speed)
                if u_loss >= p:
                    f.lost = "channel"
            self._hear(other, a0, a0 + dur, f)
        self._in_flight.append(f)

    def _hear(self, node: _Node, a0: float, a1: float, f: _Flight) -> None:
        """Register a signal at ``node`` over [a0, a1); mark the losses it causes or suffers."""
        if f.dst == node.name and f.lost is None and _overlap(node.tx_start, node.tx_end, a0, a1):
            f.lost = "half_duplex"
        for b0, b1, g in node.arrivals:
            # two senders' signals overlap here: the addressed ones collide (one sender's
            # packets follow each other on the water and never overlap, whatever the motion)
            if g.src != f.src and _overlap(b0, b1, a0, a1):
                if g.dst == node.name and g.lost is None:
                    g.lost = "collision"
                if f.dst == node.name and f.lost is None:
                    f.lost = "collision"
        node.arrivals.append((a0, a1, f))

    def _settle(self, t_s: float) -> None:
        """Close the packets whose arrival ended by ``t_s`` and forget signals that ended."""
        still, done = [], []
        for f in self._in_flight:
            (done if f.a1 <= t_s else still).append(f)
        self._in_flight = still
        done.sort(key=lambda f: (f.a1, f.id))
        for f in done:
            rec = f.record()
            self._done.append(rec)
            if rec.outcome == "delivered":
                self._nodes[f.dst].inbox.append(rec)
        for node in self._nodes.values():
            if node.arrivals:
                node.arrivals = [a for a in node.arrivals if a[1] > t_s]
