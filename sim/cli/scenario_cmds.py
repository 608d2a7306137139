"""``auvsim scenarios`` and ``auvsim validate``."""

from __future__ import annotations

import argparse
import sys

from scenarios.load import ScenarioError, list_scenarios, load_scenario
from sim.cli.errors import CliError

DEFAULT_SCENARIO = "cssn_lawnmower"


def add_scenario_args(p: argparse.ArgumentParser, *, positional: bool = True) -> None:
    """The scenario (positional, optional) and repeatable ``--set`` overrides."""
    if positional:
        p.add_argument("scenario", nargs="?", default=DEFAULT_SCENARIO,
                       help=f"shipped scenario name or YAML path (default: {DEFAULT_SCENARIO})")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="dotted override, e.g. --set vehicle.mass_kg=36 (repeatable; values parsed as YAML)")


def load_scenario_noting(name: str, overrides: list[str], command: str, flags: dict[str, str] | None = None):
    """:func:`scenarios.load.load_scenario`, its notes (a preset's defaults replacing the
    file's values) printed to stderr as ``auvsim COMMAND: note: ...``. ``flags``: override item
    -> the command-line option it came from (``--detector none``), which an error then names
    instead of ``--set``."""
    notes: list[str] = []
    try:
        scenario = load_scenario(name, overrides, notes=notes)
    except ScenarioError as exc:
        text = str(exc)
        for item, flag in (flags or {}).items():
            text = text.replace(f"(from --set {item})", f"(from {flag})")
        if text == str(exc):
            raise
        raise ScenarioError(text) from None
    for line in notes:
        print(f"auvsim {command}: note: {line}", file=sys.stderr, flush=True)
    return scenario


def refuse_sweep_only(name: str, command: str) -> None:
    """Refuse a study that runs only as ``auvsim sweep`` (``mcm_survey``) by name.

    Raises:
        CliError: ``name`` is such a study.
    """
    from sim.sweep.runner import SWEEP_ONLY

    if name in SWEEP_ONLY:
        raise CliError(f"{name}: a Monte Carlo study without a scenario file, so not for auvsim {command}; "
                       f"run it as: auvsim sweep {name} --runs N --out DIR [--set key=value] (its MuJoCo "
                       "counterpart, mcm_survey_full, also runs alone)")


def _cmd_scenarios(args: argparse.Namespace) -> int:
    from sim.sweep.runner import SWEEP_ONLY

    for name, desc in {**list_scenarios(), **SWEEP_ONLY}.items():
        print(f"{name:28s} {desc}")
    return 0


def _cmd_validate(args: argparse.Namespace) -> int:
    from scenarios.load import scenario_yaml

    refuse_sweep_only(args.scenario, "validate")
    scenario = load_scenario_noting(args.scenario, args.overrides, "validate")
    print(scenario_yaml(scenario), end="")
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("scenarios", help="list the shipped scenarios")
    p.set_defaults(func=_cmd_scenarios)

    p = sub.add_parser("validate", help="load a scenario and print it fully resolved, or the error")
    p.add_argument("scenario", help="shipped scenario name or YAML path")
    add_scenario_args(p, positional=False)
    p.set_defaults(func=_cmd_validate)
