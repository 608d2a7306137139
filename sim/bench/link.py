"""Acoustic link and message codec cost (``auvsim bench link``).

A synthetic two-vehicle survey at the autonomy rate (10 Hz): the AUV runs a 200 m x 100 m
lawnmower at 0.5 m/s, the buoy follows 20 m behind it at the surface; the AUV sends a
detection report (33 bytes) on average every ``detection_period_s`` and the buoy a USBL fix
report (38 bytes) every ``fix_period_s``, on the default S2CR 18/34-class link. Timed on one
core: the link calls of every tick (``advance``, ``delivered``, ``send``, payloads encoded
beforehand) with and without the traffic, giving the cost per tick and per message, and the
messages' encoding and decoding on their own; each the fastest of ``repeats`` runs (as
``timeit``), so other processes on a shared machine do not count as link cost.
"""

from __future__ import annotations

import time

import numpy as np

from autonomy.comms.messages import DetectionReport, UsblFixReport, decode
from autonomy.geodesy import GeodeticOrigin, ned_to_lat_lon_depth
from scenarios.config.comms import AcousticLinkConfig
from sim.comms import AcousticLink

_SPEED_MPS = 0.5
_RATE_HZ = 10.0
_EPOCH_UNIX_S = 1_602_000_000.0


def _auv_track(t: np.ndarray) -> np.ndarray:
    """(n, 3) NED lawnmower: 200 m legs east-west, 20 m apart northwards, 4 m deep."""
    s = _SPEED_MPS * t
    period = 440.0  # 200 m leg + 20 m step, twice
    leg = np.mod(s, period)
    east = np.where(leg < 200, leg, np.where(leg < 220, 200.0, np.where(leg < 420, 420.0 - leg, 0.0)))
    north = 40.0 * np.floor(s / period) + np.clip(leg - 200.0, 0, 20) + np.clip(leg - 420.0, 0, 20)
    return np.column_stack([north, east, np.full_like(t, 4.0)])


def _traffic(duration_s: float, detection_period_s: float, fix_period_s: float, seed: int) -> dict:
    """Positions at every tick and the encoded messages each vehicle sends at it."""
    origin = GeodeticOrigin()
    t = np.arange(0.0, duration_s, 1.0 / _RATE_HZ)
    auv = _auv_track(t)
    buoy = _auv_track(np.maximum(t - 20.0 / _SPEED_MPS, 0.0)) * [1, 1, 0]
    auv_lld, buoy_lld = ned_to_lat_lon_depth(auv, origin), ned_to_lat_lon_depth(buoy, origin)
    detect = np.random.default_rng(seed).random(len(t)) < 1.0 / (detection_period_s * _RATE_HZ)
    fix_every = max(int(round(fix_period_s * _RATE_HZ)), 1)
    cov = np.diag([0.25, 0.16, 0.04])
    sends: dict[int, list[tuple[str, str, bytes]]] = {}
    for k, tk in enumerate(t.tolist()):
        a, b = auv_lld[k], buoy_lld[k]
        if detect[k]:
            msg = DetectionReport(k % 65536, _EPOCH_UNIX_S + tk, a[0], a[1], a[2], cov, 0, 1.0, 0.8)
            sends.setdefault(k, []).append(("auv", "buoy", msg.encode()))
        if k % fix_every == 0:
            fix = UsblFixReport(k % 65536, _EPOCH_UNIX_S + tk, a[0], a[1], a[2], cov, b[0], b[1])
            sends.setdefault(k, []).append(("buoy", "auv", fix.encode()))
    return {"t": t.tolist(), "pos": [{"auv": auv[k], "buoy": buoy[k]} for k in range(len(t))], "sends": sends}


def _drive(traffic: dict, seed: int, with_traffic: bool) -> tuple[float, dict]:
    """Wall time of the link calls over the ticks (payloads ready), and the link statistics."""
    link = AcousticLink.from_config(AcousticLinkConfig(enabled=True), ["auv", "buoy"], seed)
    speeds = {"auv": _SPEED_MPS, "buoy": _SPEED_MPS}
    sends = traffic["sends"] if with_traffic else {}
    t0 = time.perf_counter()
    for k, (tk, pos) in enumerate(zip(traffic["t"], traffic["pos"])):
        link.advance(tk, pos, speeds)
        link.delivered(tk)
        for src, dst, payload in sends.get(k, ()):
            link.send(tk, src, dst, payload)
    return time.perf_counter() - t0, link.stats().to_dict()


def _codec_us(n: int = 2000) -> tuple[float, float]:
    msg = DetectionReport(1, _EPOCH_UNIX_S, 44.09, 9.86, 4.0, np.diag([0.25, 0.16, 0.04]), 0, 1.0, 0.8)
    t0 = time.perf_counter()
    for _ in range(n):
        data = msg.encode()
    t1 = time.perf_counter()
    for _ in range(n):
        decode(data)
    t2 = time.perf_counter()
    return (t1 - t0) / n * 1e6, (t2 - t1) / n * 1e6


def measure(duration_s: float = 1800.0, detection_period_s: float = 5.0, fix_period_s: float = 2.0,
            seed: int = 0, repeats: int = 3) -> dict:
    """Cost per message and per tick of driving the link, the codec's cost, and the link statistics."""
    traffic = _traffic(duration_s, detection_period_s, fix_period_s, seed)
    n_ticks = len(traffic["t"])
    n_msgs = sum(len(v) for v in traffic["sends"].values())
    busy = min(_drive(traffic, seed, True)[0] for _ in range(max(repeats, 1)))
    idle = min(_drive(traffic, seed, False)[0] for _ in range(max(repeats, 1)))
    stats = _drive(traffic, seed, True)[1]
    enc_us, dec_us = _codec_us()
    return {
        "sim_time_s": duration_s,
        "ticks": n_ticks,
        "messages_sent": n_msgs,
        "link_us_per_message": (busy - idle) / max(n_msgs, 1) * 1e6,
        "link_us_per_tick_idle": idle / n_ticks * 1e6,
        "link_us_per_tick_with_traffic": busy / n_ticks * 1e6,
        "encode_us_per_message": enc_us,
        "decode_us_per_message": dec_us,
        "link_wall_s_per_hour_simulated": busy / duration_s * 3600.0,
        **{f"link_{k}": v for k, v in stats.items()},
        "repeats": repeats,
    }


def run(seed: int = 0) -> dict:
    """Headline figures: a 30-minute survey."""
    return measure(seed=seed)


if __name__ == "__main__":
    import json

    print(json.dumps(run(), indent=2))
