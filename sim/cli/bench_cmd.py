"""``auvsim bench NAME``: run one benchmark and print its figures."""

from __future__ import annotations

import argparse
import importlib
import inspect
import json
import sys

from sim.bench import BENCHES
from sim.cli.args import non_negative_int, positive_int
from sim.cli.errors import CliError
from sim.cli.scenario_cmds import DEFAULT_SCENARIO, add_scenario_args, load_scenario_noting, refuse_sweep_only

SLOW_BENCHES = ("mission", "gym", "vector", "export", "dataset", "atr", "fls")  # a minute or more
OPTION_BENCHES = {"workers": ("mission", "gym", "dataset", "vector"), "sonar": ("mission",), "model": ("atr",)}  # benches taking each option


def _cmd_bench(args: argparse.Namespace) -> int:
    module_name, func_name, _ = BENCHES[args.name]
    overrides = list(args.overrides)
    if args.seed is not None:
        overrides.append(f"seed={args.seed}")
    refuse_sweep_only(args.scenario, "bench")
    scenario = load_scenario_noting(args.scenario, overrides, "bench")
    module = importlib.import_module(module_name)
    bench = getattr(module, func_name)
    if hasattr(module, "check_scenario"):  # before the "running" line: a scenario it cannot run is one line
        module.check_scenario(scenario)
    params = inspect.signature(bench).parameters
    if "scenario" not in params and (args.scenario != DEFAULT_SCENARIO or args.overrides):
        what = "--scenario" if args.scenario != DEFAULT_SCENARIO else "--set"
        raise CliError(f"{what}: bench {args.name} does not fly a scenario of yours ({BENCHES[args.name][2]}); "
                       "leave it out (--seed is taken)")
    options = {}
    for flag, key, value, default in (("--workers", "workers", args.workers, None),
                                      ("--no-sonar", "sonar", not args.no_sonar, True),
                                      ("--model", "model", args.model, None)):
        if value == default or (key == "workers" and value is None):
            continue
        if key not in params:
            raise CliError(f"{flag}: only for bench {', '.join(OPTION_BENCHES[key])}, not {args.name}")
        options[key] = value
    if args.model is not None:
        from pathlib import Path

        if Path(args.model).is_dir():
            raise CliError(f"--model {args.model}: is a folder (give the .onnx file)")
        if not Path(args.model).is_file():
            raise CliError(f"--model {args.model}: no such ONNX file")
    if args.no_sonar and args.workers is not None and args.workers > 1:
        raise CliError("--workers: times the pipelined sonar against the serial loop; not with --no-sonar "
                       "(drop one of them)")
    what = f" on {scenario.name}" if "scenario" in params else ""
    slow = " (minutes on a loaded machine)" if args.name in SLOW_BENCHES else ""
    print(f"bench {args.name}{what}: running; its figures come at the end{slow}", file=sys.stderr, flush=True)
    if "scenario" in params:
        result = bench(scenario, **options)
    else:
        result = bench(seed=scenario.seed, **options) if "seed" in params else bench(**options)
    if args.json:
        print(json.dumps(result))
    else:
        for key, value in result.items():
            if isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
                print(f"{key}:")
                print("\n".join("  " + line for line in table_lines(value)))
            else:
                print(f"{key:28s} {value}")
    return 0


def table_lines(rows: list[dict]) -> list[str]:
    """Rows of dicts as aligned text columns (the keys of the first row, in order)."""
    keys = list(dict.fromkeys(k for r in rows for k in r))
    cells = [[str(r.get(k, "")) for k in keys] for r in rows]
    widths = [max(len(k), *(len(c[i]) for c in cells)) for i, k in enumerate(keys)]
    return ["  ".join(k.rjust(w) for k, w in zip(keys, widths))] + [
        "  ".join(c.rjust(w) for c, w in zip(row, widths)) for row in cells]


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("bench", help="run a benchmark")
    p.add_argument("name", choices=sorted(BENCHES), help="; ".join(f"{k}: {v[2]}" for k, v in BENCHES.items()))
    p.add_argument("--scenario", default=DEFAULT_SCENARIO, help="scenario name or path")
    p.add_argument("--seed", type=non_negative_int, default=None)
    p.add_argument("--json", action="store_true", help="print one JSON object as the last line")
    p.add_argument("--workers", type=positive_int, default=None, metavar="N",
                   help="mission, gym, dataset: also time N threads (mission: the pipelined loop), N "
                        "vector-env processes (gym) or N dataset worker processes against one, in the same run; "
                        "vector: the worker processes (default the cores)")
    p.add_argument("--no-sonar", action="store_true", help="mission: without the forward-looking sonar "
                                                           "(and so without perception)")
    p.add_argument("--model", default=None, metavar="FILE.onnx",
                   help="atr: also time this ATR model against the shipped one, alternating, in CPU seconds "
                        "(model_cpu_ratio)")
    add_scenario_args(p, positional=False)
    p.set_defaults(func=_cmd_bench)
