"""``auvsim bench NAME``: run one benchmark and print its figures."""

from __future__ import annotations

import argparse
import importlib
import inspect
import json

from scenarios.load import load_scenario
from sim.cli.args import non_negative_int
from sim.cli.scenario_cmds import DEFAULT_SCENARIO, add_scenario_args

# bench name -> (module, function, help). The function takes the scenario (or only a seed)
# and returns a dict.
BENCHES: dict[str, tuple[str, str, str]] = {
    "physics": ("sim.bench_physics", "run", "hull + hydrodynamics + thrusters at the physics rate"),
    "fls": ("sim.bench_fls", "run", "forward-looking sonar frame rendering"),
    "sss": ("sim.bench_sss", "run", "side-scan sonar ping rendering (1000 bins per side)"),
    "mission": ("sim.bench_mission", "run", "closed-loop mission, sensors and FLS included"),
    "pmha": ("sim.bench_pmha", "run", "PMHA world-model update time"),
    "gym": ("sim.bench_gym", "run", "gymnasium environment step rate"),
    "atr": ("sim.evaluation.atr_metrics", "bench_atr", "ATR inference frame rate (CNN and classical)"),
}


def _cmd_bench(args: argparse.Namespace) -> int:
    module_name, func_name, _ = BENCHES[args.name]
    overrides = list(args.overrides)
    if args.seed is not None:
        overrides.append(f"seed={args.seed}")
    scenario = load_scenario(args.scenario, overrides)
    bench = getattr(importlib.import_module(module_name), func_name)
    params = inspect.signature(bench).parameters
    if "scenario" in params:
        result = bench(scenario)
    else:
        result = bench(seed=scenario.seed) if "seed" in params else bench()
    if args.json:
        print(json.dumps(result))
    else:
        for key, value in result.items():
            print(f"{key:28s} {value}")
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("bench", help="run a benchmark")
    p.add_argument("name", choices=sorted(BENCHES), help="; ".join(f"{k}: {v[2]}" for k, v in BENCHES.items()))
    p.add_argument("--scenario", default=DEFAULT_SCENARIO, help="scenario name or path")
    p.add_argument("--seed", type=non_negative_int, default=None)
    p.add_argument("--json", action="store_true", help="print one JSON object as the last line")
    add_scenario_args(p, positional=False)
    p.set_defaults(func=_cmd_bench)
