"""``auvsim sweep SCENARIO --runs N --out DIR``: a resumable Monte Carlo sweep."""

from __future__ import annotations

import argparse

from sim.cli.args import non_negative_int, positive_int


def _cmd_sweep(args: argparse.Namespace) -> int:
    from sim.sweep.runner import SweepSpec, parse_grid, parse_overrides, run_grid, run_sweep

    spec = SweepSpec(scenario=args.scenario, runs=args.runs, seed=args.seed, overrides=parse_overrides(args.overrides))
    kwargs = {"workers": args.workers, "use_ray": args.ray is not None, "ray_address": args.ray or None,
              "progress": not args.no_progress}
    if args.grid:
        summary = run_grid(args.out, spec, parse_grid(args.grid), **kwargs)
    else:
        summary = run_sweep(args.out, spec, **kwargs)
    n = summary["runs"]
    print(f"sweep: wrote {args.out} ({n} run{'' if n == 1 else 's'})")
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("sweep", help="resumable Monte Carlo sweep of a scenario (one JSON line per run)")
    p.add_argument("scenario", help="scenario with a Monte Carlo runner: mcm_survey (kinematic), mcm_survey_full, "
                                    "or a scenario file with mcm.mode: full")
    p.add_argument("--runs", type=positive_int, required=True,
                   help="number of runs (>= 1; more than an earlier sweep in --out holds extends it)")
    p.add_argument("--out", required=True, help="sweep folder: new, or an earlier sweep to resume or extend")
    p.add_argument("--seed", type=non_negative_int, default=0, help="run i uses seed + i")
    p.add_argument("--workers", type=positive_int, default=1, help="local processes (without --ray)")
    p.add_argument("--ray", nargs="?", const="", default=None, metavar="ADDRESS",
                   help="run on Ray: a local instance, or the running cluster at ADDRESS")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override, repeatable, values parsed as YAML: mcm_survey's flat keys (--set n_particles=300), "
                        "a scenario file's dotted keys (--set mcm.mapper.n_particles=300)")
    p.add_argument("--grid", action="append", default=[], metavar="KEY=V1,V2|FILE.yaml",
                   help="parameter grid: every combination runs --runs runs into its own sub-folder "
                        "(repeatable; or a YAML file mapping keys to value lists)")
    p.add_argument("--no-progress", action="store_true")
    p.set_defaults(func=_cmd_sweep)
