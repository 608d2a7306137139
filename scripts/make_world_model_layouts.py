"""Write the world-model stress layouts: the CSSN survey with 3, 8 and 12 mixed-shape targets.

Each layout keeps ``cssn_lawnmower``'s survey (legs N = 8 .. -8, E 0 .. 32) and puts targets
of every shape at random, at least ``--min-separation-m`` apart, inside the surveyed area, on
a seabed sloping ``--slope-deg`` (each target's base at the seabed depth under it), with a
constant current. Deterministic for a given ``--seed``.

    python scripts/make_world_model_layouts.py --out scripts/world_model_layouts
    python scripts/evaluate_world_model.py --scenario scripts/world_model_layouts/mixed8.yaml \\
        --configs cnn_estimate_eq6 --seeds 5 --out runs/wm_mixed8
"""

from __future__ import annotations

import argparse
import copy
import math
from pathlib import Path

import numpy as np
import yaml

SHAPES = (
    {"shape": "half_sphere", "radius_m": 0.5},
    {"shape": "truncated_cone", "radius_m": 0.5, "top_radius_m": 0.2, "height_m": 0.6},
    {"shape": "cylinder", "radius_m": 0.3, "height_m": 0.9, "rpy_deg": [90.0, 0.0, 30.0]},
    {"shape": "box", "size_m": [0.8, 0.5, 0.4], "rpy_deg": [0.0, 0.0, 40.0]},
    {"shape": "tyre", "radius_m": 0.45, "tube_radius_m": 0.15},
)
#: one-sigma spread of the leading edge's distance before an object's centre against the
#: localisation's 0.5 m range offset, over SHAPES (the inspection planner's reference bias)
REFERENCE_BIAS_SIGMA_M = 0.3
AREA_N_M = (-7.0, 7.0)  # inside the legs at N = 8 .. -8
AREA_E_M = (3.0, 29.0)  # inside the legs' E 0 .. 32


def layout(n_targets: int, rng: np.random.Generator, min_sep_m: float, slope_deg: float,
           slope_azimuth_deg: float, depth_m: float, center_ne_m: tuple[float, float]) -> list[dict]:
    pts: list[np.ndarray] = []
    while len(pts) < n_targets:
        p = np.array([rng.uniform(*AREA_N_M), rng.uniform(*AREA_E_M)])
        if all(np.linalg.norm(p - q) >= min_sep_m for q in pts):
            pts.append(p)
    k = math.tan(math.radians(slope_deg))
    az = math.radians(slope_azimuth_deg)
    targets = []
    for i, (n, e) in enumerate(pts):
        depth = depth_m + k * ((n - center_ne_m[0]) * math.cos(az) + (e - center_ne_m[1]) * math.sin(az))
        shape = dict(SHAPES[i % len(SHAPES)])
        targets.append({"name": f"T{i + 1}_{shape['shape']}", **shape,
                        "pos_ned": [round(float(n), 2), round(float(e), 2), round(float(depth), 3)]})
    return targets


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="scripts/world_model_layouts")
    ap.add_argument("--counts", type=int, nargs="*", default=[3, 8, 12])
    ap.add_argument("--seed", type=int, default=12)
    ap.add_argument("--min-separation-m", type=float, default=2.5)
    ap.add_argument("--slope-deg", type=float, default=3.0)
    ap.add_argument("--current-mps", type=float, default=0.2)
    args = ap.parse_args()
    from scenarios import load_scenario
    from scenarios.load import resolve_path

    base = yaml.safe_load(resolve_path("cssn_lawnmower").read_text())
    seabed = base["world"]["seabed"]
    center = tuple(seabed["center_ne_m"])
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for n in args.counts:
        rng = np.random.default_rng([args.seed, n])
        scn = copy.deepcopy(base)
        scn["description"] = (f"CSSN survey over {n} mixed-shape targets >= {args.min_separation_m} m apart on a "
                              f"{args.slope_deg} deg slope with a {args.current_mps} m/s current")
        scn["world"]["seabed"].update({"kind": "slope", "slope_deg": args.slope_deg, "slope_azimuth_deg": 0.0})
        scn["world"]["targets"] = layout(n, rng, args.min_separation_m, args.slope_deg, 0.0,
                                         float(seabed["depth_m"]), center)
        c = args.current_mps / math.sqrt(2.0)  # from the south-west, across the east-west legs
        scn["world"]["current"] = {"velocity_ned_mps": [round(c, 4), round(c, 4), 0.0]}
        # objects of several sizes (radii 0.15-0.5 m) against the one 0.5 m range offset: when the
        # inspection planner is switched on, its look model carries that leading-edge bias
        scn["autonomy"]["guidance"]["inspection"] = {"reference_bias_sigma_m": REFERENCE_BIAS_SIGMA_M}
        path = out / f"mixed{n}.yaml"
        path.write_text(yaml.safe_dump(scn, sort_keys=False, default_flow_style=None))
        load_scenario(str(path))  # validates
        print(path)


if __name__ == "__main__":
    main()
