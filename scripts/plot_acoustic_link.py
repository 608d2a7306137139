"""Plot the acoustic link's loss curve against measured loss, and its latency: docs/acoustic_link.png.

Left: delivery probability against range of the scenario's ``comms.acoustic`` settings
(both ends at rest, and both under way at 0.5 m/s), with the delivered fraction of 2000
seeded packets at each of several ranges (4-sigma binomial bars). Right: latency of the
packets of the ``auvsim bench link`` survey (detections AUV -> buoy, USBL fixes buoy -> AUV).

Usage: python scripts/plot_acoustic_link.py [SCENARIO] [--out PATH] [--seed N]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from scenarios import load_scenario  # noqa: E402
from scenarios.config.comms import AcousticLinkConfig  # noqa: E402
from sim.bench.link import _traffic  # noqa: E402
from sim.comms import AcousticLink  # noqa: E402


def delivered_fraction(cfg: AcousticLinkConfig, range_m: float, speed_mps: float, n: int, seed: int) -> float:
    """Fraction of ``n`` back-to-back packets delivered over ``range_m`` (static geometry)."""
    cfg = cfg.model_copy(update={"queue_limit": max(n, cfg.queue_limit)})
    link = AcousticLink.from_config(cfg, ["a", "b"], seed)
    pos = {"a": np.zeros(3), "b": np.array([range_m, 0.0, 0.0])}
    speeds = {"a": speed_mps, "b": speed_mps}
    link.advance(0.0, pos, speeds)
    for _ in range(n):
        link.send(0.0, "a", "b", b"\x00")
    link.advance(n * cfg.packet_duration_s(1) + range_m / cfg.sound_speed_mps + 1.0, pos, speeds)
    return link.stats().delivered / n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario", nargs="?", default="cssn_lawnmower")
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / "docs" / "acoustic_link.png")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    cfg = load_scenario(args.scenario).comms.acoustic

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    r = np.linspace(0.0, 2.0 * cfg.loss_range50_m, 300)
    n = 2000
    for speed, colour in ((0.0, "tab:blue"), (0.5, "tab:orange")):
        ax.plot(r, [cfg.delivery_prob(x, speed, speed) for x in r], color=colour,
                label=f"configured, both ends at {speed} m/s")
        ranges = np.linspace(0.1, 1.9, 7) * cfg.loss_range50_m
        meas = [delivered_fraction(cfg, x, speed, n, args.seed + i) for i, x in enumerate(ranges)]
        p = np.array([cfg.delivery_prob(x, speed, speed) for x in ranges])
        ax.errorbar(ranges, meas, yerr=4 * np.sqrt(p * (1 - p) / n), fmt="o", color=colour, capsize=3,
                    label=f"{n} seeded packets (4-sigma band)")
    ax.set(xlabel="range (m)", ylabel="delivery probability", ylim=(-0.02, 1.02),
           title=f"Loss: logistic in range, self-noise per moving end ({cfg.bit_rate_bps:.0f} bit/s)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)

    traffic = _traffic(1800.0, 5.0, 2.0, args.seed)
    link = AcousticLink.from_config(cfg, ["auv", "buoy"], args.seed)
    for k, (tk, pos) in enumerate(zip(traffic["t"], traffic["pos"])):
        link.advance(tk, pos, {"auv": 0.5, "buoy": 0.5})
        for src, dst, payload in traffic["sends"].get(k, ()):
            link.send(tk, src, dst, payload)
    for src, label in (("auv", "detections AUV -> buoy (32 B)"), ("buoy", "USBL fixes buoy -> AUV (37 B)")):
        lat = [p.latency_s for p in link.finished() if p.src == src and p.outcome == "delivered"]
        s = link.stats(src=src)
        bx.hist(lat, bins=40, alpha=0.6, label=f"{label}: {s.delivered}/{s.sent} delivered, "
                f"p95 {s.p95_latency_s:.2f} s")
    bx.set(xlabel="latency, send to delivery (s)", ylabel="packets",
           title="30-minute survey, buoy 20 m behind (queueing, half duplex)")
    bx.legend(fontsize=8)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
