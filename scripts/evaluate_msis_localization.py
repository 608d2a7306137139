"""Localisation RMS of the Ping360 pool / tank scenarios against dead reckoning of the same run.

    python scripts/evaluate_msis_localization.py pool_circular [--seeds 1] [--set key=value ...]
"""

from __future__ import annotations

import argparse
import json
import time

from scenarios.load import load_scenario
from sim.mission import Mission
from sim.msis_evaluation import LocalizationErrorObserver


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario")
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--set", dest="overrides", action="append", default=[])
    args = ap.parse_args()
    for seed in range(args.seeds):
        scn = load_scenario(args.scenario, [*args.overrides, f"seed={seed}"])
        mission = Mission(scn)
        obs = LocalizationErrorObserver(mission)
        mission.observers.append(obs)
        t0 = time.perf_counter()
        summary = mission.run(progress=False)
        out = {"scenario": scn.name, "seed": seed, "sim_s": round(summary.sim_time_s, 1), "mode": summary.final_mode, "aborted": summary.abort_reason,
               "wall_s": round(time.perf_counter() - t0, 1), **{k: round(v, 3) for k, v in obs.rms().items()}}
        print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main()
