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


def _cmd_run(args: argparse.Namespace) -> int:
    from sim.mission.run import run_mission

    overrides = list(args.overrides)
    if args.seed is not None:
        overrides.append(f"seed={args.seed}")
    if args.detector is not None:
        overrides.append(f"autonomy.atr.detector={args.detector}")
    refuse_sweep_only(args.scenario, "run")
    scenario = load_scenario_noting(args.scenario, overrides, "run")
    rosbag = args.rosbag or scenario.outputs.rosbag
    if rosbag:
        try:
            import rosbags  # noqa: F401
        except ImportError:
            what = "--rosbag" if args.rosbag else "outputs.rosbag"
            raise CliError(f"{what}: needs the rosbags package (pip install 'auvsim[rosbag]')") from None
    ping360_log = args.ping360_log or scenario.outputs.ping360_log
    if ping360_log:
        what = "--ping360-log" if args.ping360_log else "outputs.ping360_log"
        if scenario.sensors.first_of_kind("msis") is None:
            raise CliError(f"{what}: the scenario has no sensor of kind msis (a scanning sonar) to log; "
                           "shipped ones with one: pool_circular, tank_rectangular")
        try:
            import brping  # noqa: F401
        except ImportError:
            raise CliError(f"{what}: needs the bluerobotics-ping package (pip install 'auvsim[ping]')") from None
    xtf = args.xtf or scenario.outputs.xtf
    if xtf:
        what = "--xtf" if args.xtf else "outputs.xtf"
        if scenario.sensors.first_of_kind("sss") is None:
            raise CliError(f"{what}: the scenario has no sensor of kind sss (a side-scan sonar) to export; "
                           "shipped one with one: mcm_survey_full")
        try:
            import pyxtf  # noqa: F401
        except ImportError:
            raise CliError(f"{what}: needs the pyxtf package (pip install 'auvsim[xtf]')") from None
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
