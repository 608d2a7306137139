"""``auvsim run``: fly a closed-loop survey mission and write its results."""

from __future__ import annotations

import argparse
import sys

from sim.cli.args import non_negative_int, positive_int
from sim.cli.errors import EXIT_MISSION_ABORTED, EXIT_OK, CliError
from sim.cli.scenario_cmds import add_scenario_args, load_scenario_noting, refuse_sweep_only


def _fmt(value: float | None, spec: str, unit: str = "") -> str:
    """``value`` formatted, or ``n/a`` when there is none (nothing matched)."""
    if value is None or value != value:  # None or NaN
        return "n/a"
    return f"{value:{spec}}{unit}"


def print_summary(metrics: dict, out: str) -> None:
    """The console summary of a run: rounded figures, ``n/a`` where nothing was measured."""
    nav = metrics["navigation"]
    rtf = metrics.get("real_time_factor")
    print(f"sim {metrics['sim_time_s']:.0f} s in {metrics['wall_time_s']:.1f} s wall "
          f"({_fmt(rtf, '.1f', 'x')} real time), {metrics['distance_travelled_m']:.0f} m travelled, "
          f"final nav error {_fmt(nav.get('final_position_error_m'), '.2f', ' m')}")
    if "note" in metrics.get("perception", {}):  # several sonars: say which one perception read
        per = metrics["perception"]
        counts = ", ".join(f"{k} {v}" for k, v in per["fls_frames_by_sensor"].items())
        print(f"sonar frames: {counts}; {per['note']}")
    if "world_model" in metrics:
        wm = metrics["world_model"]
        n_other = wm.get('objects_not_target', 0)
        print(f"world model: {wm['objects']} targets ({n_other} more object{'' if n_other == 1 else 's'} classified "
              f"not target), {wm['matched']} matched, {wm['missed']} missed, {wm['false']} false, "
              f"mean error {_fmt(wm.get('mean_position_error_m'), '.2f', ' m')}, GOSPA {_fmt(wm.get('gospa'), '.2f')}")
        nees = wm.get("nees_horizontal")
        if nees and nees["n"]:
            lo, hi = nees["band_95"]
            verdict = ("inside it" if lo <= nees["mean"] <= hi else
                       "below it: ellipses larger than the errors" if nees["mean"] < lo else
                       "above it: ellipses smaller than the errors")
            print(f"world model ellipses: mean horizontal NEES {nees['mean']:.2f} over {nees['n']} matched targets "
                  f"(a consistent map: 2, 95 % band {lo:.2f}-{hi:.2f}, {verdict}; one run's targets share its "
                  "navigation error, so judge over seeds)")
    if "surface_world_model" in metrics:
        wm = metrics["surface_world_model"]
        print(f"surface world model: {wm['objects']} targets, {wm['matched']} matched, {wm['missed']} missed, "
              f"{wm['false']} false, mean error {_fmt(wm.get('mean_position_error_m'), '.2f', ' m')}")
    if "link" in metrics:
        up, down = metrics["link"]["uplink_detections"], metrics["link"]["downlink_usbl_fixes"]
        for name, st in (("detections up", up), ("USBL fixes down", down)):
            pending = f", {st['pending']} still queued or in flight at the end" if st.get("pending") else ""
            print(f"link, {name}: {st['sent']} sent, {st['delivered']} delivered, {st['lost']} lost{pending}, latency mean "
                  f"{_fmt(st.get('mean_latency_s'), '.2f', ' s')}, p95 {_fmt(st.get('p95_latency_s'), '.2f', ' s')}")
        link = metrics["link"]
        held = link.get("usbl_fixes_superseded", 0) + link.get("usbl_fixes_unsent_at_end", 0)
        if held:
            reach = link.get("tdma", {}).get("surface_reach_m")
            print(f"link: {held} of {link.get('usbl_fixes_made', 0)} USBL fixes not sent: each waited for a surface "
                  f"slot it fitted, packet and travel time, until a newer fix replaced it (the slot carries a fix to "
                  f"{_fmt(reach, '.0f', ' m')}; a longer comms.surface.surface_slot_s reaches farther)")
        if link.get("unencodable"):
            print(f"link: {link['unencodable']} messages not sent: a value outside its field in message_version "
                  f"{link.get('message_version')}")
    if "tracking" in metrics and not any(v.get("n") for v in metrics["tracking"]["errors"].values()):
        tr = metrics["tracking"]
        print(f"tracking ({tr['mode']}): nothing scored (errors count from {tr.get('scored_from_s', 0):g} s into the "
              "run, once the filters have started); raise duration_s")
    elif "tracking" in metrics:
        tr = metrics["tracking"]
        errs = ", ".join(f"{k} {_fmt(v.get('mean_m'), '.2f')} +- {_fmt(v.get('std_m'), '.2f')} m"
                         for k, v in tr["errors"].items())
        print(f"tracking ({tr['mode']}; 3-D error, horizontal in metrics.json): {errs}; sonar used in "
              f"{_fmt(100 * tr['fused_sonar_step_fraction'], '.0f')} % "
              f"of steps; target in view {_fmt(100 * tr['target_in_fov_fraction'], '.0f')} %")
        if "nees_horizontal" in tr:
            nees = tr["nees_horizontal"]
            print("tracking consistency, mean horizontal NEES (2 if the filter's covariance is right, more: "
                  "overconfident): " + ", ".join(f"{k} {_fmt(v.get('mean'), '.2f')}" for k, v in nees.items()))
    if "mcm" in metrics and "note" in metrics["mcm"]:
        print(metrics["mcm"]["note"])
    elif "mcm" in metrics:
        mcm, det = metrics["mcm"], metrics["mcm"]["detector"]
        maps = ", ".join(f"{k} GOSPA {_fmt(v['final_gospa_mean'], '.1f')} ({v['final_cardinality_mean']:.0f} objects)"
                         for k, v in mcm.items() if isinstance(v, dict) and "final_gospa_mean" in v)
        print(f"mcm: {det['tiles']} tiles, detector pd {_fmt(det['pd'], '.2f')}, "
              f"{det['clutter_per_tile']:.2f} false per tile; {maps}")
    if "msis_localization" in metrics:
        ml = metrics["msis_localization"]
        print(f"msis localisation: {ml['n_fixes']} sonar position fix{'' if ml['n_fixes'] == 1 else 'es'}, horizontal RMS error "
              f"{_fmt(ml.get('rms_fused_m'), '.2f', ' m')} (dead reckoning alone "
              f"{_fmt(ml.get('rms_dead_reckoning_m'), '.2f', ' m')})")
    print(f"results in {out}")


def _cmd_run(args: argparse.Namespace) -> int:
    from sim.outputs.mission_outputs import run_mission

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
    fls_every = args.rosbag_fls_every if args.rosbag_fls_every is not None else scenario.outputs.rosbag_fls_every
    metrics = run_mission(scenario, args.out, nav_source=args.nav, rerun=not args.no_rerun,
                          overwrite=args.overwrite, progress=not args.quiet, rosbag=rosbag,
                          rosbag_fls_every=fls_every, score_detections=not args.no_scoring,
                          workers=args.workers)
    print_summary(metrics, args.out)
    mission = metrics["mission"]
    if mission["aborted"]:
        print(f"ABORTED: {mission['abort_reason']}", file=sys.stderr)
        return EXIT_MISSION_ABORTED
    if not mission["finished"] and "tracking" not in metrics:  # a tracking mission ends at duration_s
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
