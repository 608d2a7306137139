"""``auvsim run``: fly a closed-loop survey mission and write its results."""

from __future__ import annotations

import argparse
import sys

from sim.cli.args import non_negative_int, positive_int
from sim.cli.errors import EXIT_MISSION_ABORTED, EXIT_OK, CliError
from sim.cli.scenario_cmds import add_scenario_args, load_scenario_noting, refuse_sweep_only


def print_summary(metrics: dict, out: str) -> None:
    """The console summary of a run: rounded figures, ``n/a`` where nothing was measured; the
    core line, then each feature's lines (:func:`sim.features.summary_lines`)."""
    from sim.features import summary_lines
    from sim.features.base import fmt_or_na as _fmt

    nav = metrics["navigation"]
    rtf = metrics.get("real_time_factor")
    print(f"sim {metrics['sim_time_s']:.0f} s in {metrics['wall_time_s']:.1f} s wall "
          f"({_fmt(rtf, '.1f', 'x')} real time), {metrics['distance_travelled_m']:.0f} m travelled, "
          f"final nav error {_fmt(nav.get('final_position_error_m'), '.2f', ' m')}")
    for line in summary_lines(metrics):
        print(line)
    print(f"results in {out}")


#: The optional field-format outputs: (flag, outputs key, sensor kind it needs (None: any
#: run), what that sensor is, shipped scenarios with one, module, extra).
OPTIONAL_OUTPUTS = (
    ("rosbag", "rosbag", None, "", "", "rosbags", "rosbag"),
    ("ping360_log", "ping360_log", "msis", "a scanning sonar", "pool_circular, tank_rectangular", "brping", "ping"),
    ("xtf", "xtf", "sss", "a side-scan sonar", "mcm_survey_full", "pyxtf", "xtf"),
)


def _optional_output(args: argparse.Namespace, scenario, flag: str, key: str, kind: str | None, what: str,
                     shipped: str, module: str, extra: str) -> bool:
    """Whether the run writes this output (its flag or its ``outputs`` key); CliError when it
    cannot: no sensor of its kind, or its package missing (with the extra to install)."""
    wanted = bool(getattr(args, flag)) or bool(getattr(scenario.outputs, key))
    if not wanted:
        return False
    name = f"--{flag.replace('_', '-')}" if getattr(args, flag) else f"outputs.{key}"
    if kind is not None and scenario.sensors.first_of_kind(kind) is None:
        raise CliError(f"{name}: the scenario has no sensor of kind {kind} ({what}) to write; shipped ones "
                       f"with one: {shipped}")
    import importlib.util

    if importlib.util.find_spec(module) is None:
        raise CliError(f"{name}: needs the {module} package (pip install 'auvsim[{extra}]')")
    return True


def _cmd_run(args: argparse.Namespace) -> int:
    from sim.mission.run import run_mission

    overrides = list(args.overrides)
    flags: dict[str, str] = {}
    if args.seed is not None:
        overrides.append(f"seed={args.seed}")
        flags[overrides[-1]] = f"--seed {args.seed}"
    if args.detector is not None:
        overrides.append(f"autonomy.atr.detector={args.detector}")
        flags[overrides[-1]] = f"--detector {args.detector}"
    refuse_sweep_only(args.scenario, "run")
    scenario = load_scenario_noting(args.scenario, overrides, "run", flags)
    rosbag, ping360_log, xtf = (_optional_output(args, scenario, *spec) for spec in OPTIONAL_OUTPUTS)
    fls_every = args.rosbag_fls_every if args.rosbag_fls_every is not None else scenario.outputs.rosbag_fls_every
    metrics = run_mission(scenario, args.out, nav_source=args.nav, rerun=not args.no_rerun,
                          overwrite=args.overwrite, progress=not args.quiet, rosbag=rosbag,
                          rosbag_fls_every=fls_every, score_detections=not args.no_scoring,
                          workers=args.workers, ping360_log=ping360_log, xtf=xtf)
    print_summary(metrics, args.out)
    mission = metrics["mission"]
    if mission["aborted"]:
        print(f"ABORTED: {mission['abort_reason']}", file=sys.stderr)
        return EXIT_MISSION_ABORTED
    from sim.features import runs_to_duration

    if not mission["finished"] and not runs_to_duration(scenario):  # e.g. a tracking mission ends at duration_s
        print(f"NOT FINISHED: the run reached duration_s = {metrics['sim_time_s']:g} s in mode "
              f"{mission['final_mode']} before the survey ended (raise duration_s to fly it all)", file=sys.stderr)
    return EXIT_OK


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("run", help="run a closed-loop survey mission",
                       description="Run a closed-loop survey mission. Exit status: 0 done, 2 bad input, "
                                   "3 mission aborted (outputs still written).")
    add_scenario_args(p)
    p.add_argument("--out", required=True, help="output folder (new, or an earlier run with --overwrite)")
    p.add_argument("--seed", type=non_negative_int, default=None)
    p.add_argument("--no-rerun", action="store_true", help="skip the rerun recording")
    p.add_argument("--no-scoring", action="store_true",
                   help="do not score detections against the sonar ground truth (no precision/recall in metrics.json)")
    p.add_argument("--rosbag", action="store_true",
                   help="also write a ROS 2 bag (rosbag2 folder, MCAP storage) into OUT/rosbag")
    p.add_argument("--rosbag-fls-every", type=positive_int, default=None, metavar="N",
                   help="export every N-th sonar frame into the bag (default: the scenario's "
                        "outputs.rosbag_fls_every, 1: all; frames are ~0.8 MB)")
    p.add_argument("--ping360-log", action="store_true",
                   help="also write the scanning sonar's pings as Blue Robotics ping-protocol PING360_DEVICE_DATA "
                        "messages into OUT/ping360/ (needs a sensor of kind msis and the ping extra)")
    p.add_argument("--xtf", action="store_true",
                   help="also write the side-scan pings as an eXtended Triton Format file per sensor into OUT/xtf/ "
                        "(needs a sensor of kind sss and the xtf extra)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an earlier run's output folder (only a folder written by auvsim run)")
    p.add_argument("--nav", choices=["estimate", "truth"], default="estimate",
                   help="pose used for target geolocalisation (default: estimate)")
    p.add_argument("--detector", choices=["cnn", "classical", "none"], default=None,
                   help="override autonomy.atr.detector")
    p.add_argument("--workers", type=positive_int, default=1, metavar="N",
                   help="processes for the loop (default 1: serial); 2 or more render the sonar and run "
                        "perception in two worker processes while physics and navigation advance (same results)")
    p.add_argument("--quiet", action="store_true", help="no progress display")
    p.set_defaults(func=_cmd_run)
