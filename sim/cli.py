"""The ``auvsim`` command line.

Subcommands: ``scenarios``, ``validate``, ``run``, ``bench``, ``dataset``, ``train-atr``,
``eval-atr``. Scenario and input errors print one clear message and exit 2, no traceback.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
from collections.abc import Callable, Sequence
from typing import Any

from scenarios.load import ScenarioError, list_scenarios, load_scenario

DEFAULT_SCENARIO = "cssn_lawnmower"

# bench name -> (module, function, help). The function takes the scenario (or only a seed)
# and returns a dict.
BENCHES: dict[str, tuple[str, str, str]] = {
    "physics": ("sim.bench_physics", "run", "hull + hydrodynamics + thrusters at the physics rate"),
    "fls": ("sim.bench_fls", "run", "forward-looking sonar frame rendering"),
    "mission": ("sim.bench_mission", "run", "closed-loop mission, sensors and FLS included"),
    "pmha": ("sim.bench_pmha", "run", "PMHA world-model update time"),
    "gym": ("sim.bench_gym", "run", "gymnasium environment step rate"),
    "atr": ("sim.atr_eval", "bench_atr", "ATR inference frame rate (CNN and classical)"),
}


class CliError(Exception):
    """A user error the CLI reports as one line, exit status 2."""


def _add_scenario_args(p: argparse.ArgumentParser, *, positional: bool = True) -> None:
    if positional:
        p.add_argument("scenario", nargs="?", default=DEFAULT_SCENARIO,
                       help=f"shipped scenario name or YAML path (default: {DEFAULT_SCENARIO})")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="dotted override, e.g. --set vehicle.mass_kg=36 (repeatable)")


def _cmd_scenarios(args: argparse.Namespace) -> int:
    for name, desc in list_scenarios().items():
        print(f"{name:28s} {desc}")
    return 0


def _cmd_validate(args: argparse.Namespace) -> int:
    import yaml

    scenario = load_scenario(args.scenario, args.overrides)
    print(yaml.safe_dump(scenario.model_dump(mode="json"), sort_keys=False), end="")
    return 0


def _cmd_bench(args: argparse.Namespace) -> int:
    module_name, func_name, _ = BENCHES[args.name]
    bench = getattr(importlib.import_module(module_name), func_name)
    overrides = list(args.overrides)
    if args.seed is not None:
        overrides.append(f"seed={args.seed}")
    scenario = load_scenario(args.scenario, overrides)
    import inspect

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


def _cmd_run(args: argparse.Namespace) -> int:
    from sim.mission_cli import run_mission_command

    return run_mission_command(args)


def _register_optional(sub: argparse._SubParsersAction, module_name: str) -> None:
    """Let a module add its own subcommand (``add_parser(subparsers)``) if it exists."""
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name and exc.name.startswith(("sim", "autonomy")):
            return
        raise
    module.add_parser(sub)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="auvsim", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("scenarios", help="list the shipped scenarios")
    p.set_defaults(func=_cmd_scenarios)

    p = sub.add_parser("validate", help="load a scenario and print it fully resolved")
    p.add_argument("scenario", help="shipped scenario name or YAML path")
    _add_scenario_args(p, positional=False)
    p.set_defaults(func=_cmd_validate)

    p = sub.add_parser("bench", help="run a benchmark")
    p.add_argument("name", choices=sorted(BENCHES), help="; ".join(f"{k}: {v[2]}" for k, v in BENCHES.items()))
    p.add_argument("--scenario", default=DEFAULT_SCENARIO, help="scenario name or path")
    p.add_argument("--seed", type=int, default=None)
    p.add_argument("--json", action="store_true", help="print one JSON object as the last line")
    _add_scenario_args(p, positional=False)
    p.set_defaults(func=_cmd_bench)

    p = sub.add_parser("run", help="run a closed-loop survey mission")
    _add_scenario_args(p)
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--seed", type=int, default=None)
    p.add_argument("--no-rerun", action="store_true", help="skip the rerun recording")
    p.add_argument("--overwrite", action="store_true", help="replace an existing, non-empty --out")
    p.add_argument("--nav", choices=["estimate", "truth"], default="estimate",
                   help="pose used for target geolocalisation (default: estimate)")
    p.add_argument("--detector", choices=["cnn", "classical", "none"], default=None,
                   help="override autonomy.atr.detector")
    p.set_defaults(func=_cmd_run)

    for module_name in ("sim.dataset.generate", "sim.training.train", "sim.atr_eval"):
        _register_optional(sub, module_name)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    func: Callable[[argparse.Namespace], int] = args.func
    try:
        return int(func(args) or 0)
    except (ScenarioError, CliError) as exc:
        print(f"auvsim: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("auvsim: interrupted", file=sys.stderr)
        return 130


def fail(message: str) -> Any:
    """Raise a :class:`CliError` (for subcommand modules)."""
    raise CliError(message)


if __name__ == "__main__":
    sys.exit(main())
