"""Picture of a diver's bubble plume as the simulator moves it (PNG): top and side views of
the breaths in the water at one instant, for a diver swimming east across a horizontal
ARIS 3000's view 8 m ahead in a 0.15 m/s tidal stream towards the south-east, with the 14 deg
vertical beam's half-height at that range and the distance a breath must lie from the diver's
body to make a sonar cluster of its own.

    python scripts/plot_bubble_plume.py --out docs/bubble_plume.png --t 42
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from scenarios.config.movers import BubbleConfig, MoverConfig  # noqa: E402
from sim.scene.movers import DIVER_HALF_LENGTH_M, DIVER_RADIUS_M  # noqa: E402
from sim.scene.target_motion import BubblePlumes, ManoeuvreTrajectory, WaterDrift  # noqa: E402


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, default=Path("bubble_plume.png"))
    p.add_argument("--current", type=float, default=0.15, help="stream speed towards the south-east, m/s")
    p.add_argument("--surge", type=float, default=0.25, help="diver's speed east, m/s")
    p.add_argument("--t", type=float, default=40.0, help="instant shown, s")
    args = p.parse_args()
    if not (0.0 <= args.current <= 3.0 and 0.0 <= args.surge <= 3.0 and 10.0 <= args.t <= 100.0):
        print("plot_bubble_plume: --current and --surge must lie in [0, 3] m/s and --t in [10, 100] s", file=sys.stderr)
        return 2
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    depth, rng_m = 5.0, 8.0
    cfg = MoverConfig(name="diver", initial_pos_ned=(rng_m, -args.surge * args.t, depth), initial_course_deg=90.0,
                      surge_mps=args.surge, surge_sigma_mps=0.0, course_rate_sigma_dps=0.0, heave_sigma_mps=0.0,
                      leash_radius_m=1000.0, depth_band_m=(1.0, 10.0))
    traj = ManoeuvreTrajectory(cfg, np.random.default_rng(0), 120.0)
    cur = args.current * np.array([-math.sqrt(0.5), math.sqrt(0.5), 0.0])
    plume = BubblePlumes(BubbleConfig(), traj, np.random.default_rng(1), 120.0, drift=WaterDrift(cur))
    _, ages, pts, wet = plume.breaths_at(args.t)
    diver, _ = traj.pose_at(args.t)
    half_beam = rng_m * math.tan(math.radians(7.0))
    apart = DIVER_RADIUS_M + 0.5 + plume.cfg.radius_m

    fig = Figure(figsize=(11, 4.5))
    FigureCanvasAgg(fig)
    top, side = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    body_e = diver[1] + DIVER_HALF_LENGTH_M * np.array([-1.0, 1.0])
    track_e = np.linspace(diver[1] - args.surge * 12.0, diver[1], 2)
    top.plot(track_e, [diver[0]] * 2, ":", color="0.5", lw=1, label="diver's track (last 12 s)")
    top.plot(body_e, [diver[0]] * 2, "-", color="tab:blue", lw=8, solid_capstyle="round", alpha=0.7, label="diver")
    top.fill_between([body_e[0] - apart, body_e[1] + apart], diver[0] - apart, diver[0] + apart, color="tab:blue",
                     alpha=0.08, label=f"within {apart:.2f} m of the body: merges with its echo")
    side.plot(body_e, [depth] * 2, "-", color="tab:blue", lw=8, solid_capstyle="round", alpha=0.7)
    side.axhspan(depth - half_beam, depth + half_beam, color="tab:orange", alpha=0.12,
                 label=f"14 deg beam at {rng_m:g} m (+-{half_beam:.2f} m)")
    for k in range(len(ages)):
        ok = wet[k]
        sc = top.scatter(pts[k, ok, 1], pts[k, ok, 0], c=np.full(ok.sum(), ages[k]), vmin=0, vmax=plume.cfg.lifetime_s,
                         cmap="viridis", s=18)
        side.scatter(pts[k, ok, 1], pts[k, ok, 2], c=np.full(ok.sum(), ages[k]), vmin=0, vmax=plume.cfg.lifetime_s,
                     cmap="viridis", s=18)
    top.annotate("", xy=(diver[1] + 1.2 + cur[1] * 5, diver[0] + 1.2 + cur[0] * 5), xytext=(diver[1] + 1.2, diver[0] + 1.2),
                 arrowprops=dict(arrowstyle="->", color="k"))
    top.text(diver[1] + 1.25, diver[0] + 1.3, f"stream {args.current:g} m/s (5 s)", fontsize=7)
    top.set_xlabel("east (m)")
    top.set_ylabel("north (m): range from the sonar")
    top.set_title("top view (the sonar's plane)")
    for ax in (top, side):
        ax.set_xlim(diver[1] - 3.5, diver[1] + 2.5)
        ax.grid(alpha=0.3)
    top.set_ylim(diver[0] - 2.0, diver[0] + 2.0)
    side.set_ylim(depth + 1.5, depth - 3.0)
    top.legend(fontsize=7, loc="lower left")
    side.set_xlabel("east (m)")
    side.set_ylabel("depth (m)")
    side.set_title("side view")
    side.legend(fontsize=7, loc="lower left")
    fig.colorbar(sc, ax=[top, side], label="breath age (s)", shrink=0.8)
    fig.suptitle(f"bubble plume at t = {args.t:g} s: diver at {args.surge:g} m/s east, breath every ~4.5 s", fontsize=9)
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
