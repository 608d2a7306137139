"""Localisation RMS of the Ping360 pool / tank scenarios against dead reckoning of the same run.

    python scripts/evaluate_msis_localization.py pool_circular [--seeds 1] [--set key=value ...]
"""

from __future__ import annotations

import json
import time

from scenarios.load import load_scenario
from sim.cli.app import run_script, script_parser
from sim.cli.args import positive_int
from sim.cli.errors import CliError
from sim.mission import Mission
from sim.features import MsisLocalizationFeature


def check_localizes(scenario_arg: str, overrides: list[str]) -> None:
    """Refuse, before any run, a scenario without an enabled msis sensor and a localisation
    method (nothing to evaluate).

    Raises:
        CliError: naming the scenario and what it lacks; ScenarioError: it does not load.
    """
    scn = load_scenario(scenario_arg, overrides)
    if scn.sensors.first_of_kind("msis") is None or scn.autonomy.msis_localization.method == "none":
        raise CliError(f"{scenario_arg}: has no enabled msis sensor with autonomy.msis_localization.method "
                       "circle or walls; nothing to evaluate (shipped: pool_circular, tank_rectangular)")


def evaluate(args) -> int:
    check_localizes(args.scenario, args.overrides)
    for seed in range(args.seeds):
        scn = load_scenario(args.scenario, [*args.overrides, f"seed={seed}"])
        mission = Mission(scn)
        obs = mission.feature(MsisLocalizationFeature).error_observer()
        mission.observers.append(obs)
        t0 = time.perf_counter()
        summary = mission.run(progress=False)
        out = {"scenario": scn.name, "seed": seed, "sim_s": round(summary.sim_time_s, 1), "mode": summary.final_mode, "aborted": summary.abort_reason,
               "wall_s": round(time.perf_counter() - t0, 1), **{k: round(v, 3) for k, v in obs.rms().items()}}
        print(json.dumps(out), flush=True)
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = script_parser("evaluate_msis_localization.py", __doc__.splitlines()[0])
    ap.add_argument("scenario", help="a scenario with an msis sensor (shipped: pool_circular, tank_rectangular)")
    ap.add_argument("--seeds", type=positive_int, default=1, help="run seeds 0 to N-1 (default 1)")
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    return run_script(ap, evaluate, argv)


if __name__ == "__main__":
    raise SystemExit(main())
