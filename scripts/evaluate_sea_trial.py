"""Sea-trial evaluation over seeds: the world model on the surface against the
onboard one, the AUV's navigation with the buoy's USBL fixes against DVL-only, and the
wall-time share of the acoustic link and the second vehicle.

For each seed, ``cssn_sea_trial`` is flown once; the DVL-only estimate comes from a second
navigation filter fed the same sensor messages without the fixes
(:class:`sim.evaluation.nav_baseline.DvlOnlyBaseline`), so both figures are of the same run.
Writes ``sea_trial_eval.json`` and ``sea_trial_eval.png`` into ``--out``.

    python scripts/evaluate_sea_trial.py --seeds 0-9 --out /tmp/sea_eval --workers 2
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from scenarios.load import load_scenario  # noqa: E402
from sim.cli.app import run_script, script_parser  # noqa: E402
from sim.cli.errors import CliError  # noqa: E402
from sim.outputs.json_files import standard_json  # noqa: E402
from sim.sweep.runner import run_jobs  # noqa: E402

#: Stages counted as the cost of the link and of the second vehicle.
LINK_STAGES = ("link", "nav_late_fix")
VEHICLE_STAGES = ("surface_vehicles",)
SURFACE_WM_STAGES = ("surface_world_model",)


def parse_seeds(text: str) -> list[int]:
    """``"0-9"``, ``"0,3,5"`` or ``"10"`` (seeds 0..9) -> list of seeds.

    Raises:
        ValueError: not of those forms.
    """
    text = text.strip()
    allowed = f"--seeds {text!r}: give N (seeds 0..N-1), A-B or a comma list of seeds >= 0"
    try:
        if "-" in text:
            a, b = (int(v) for v in text.split("-", 1))
            seeds = list(range(a, b + 1))
        elif "," in text:
            seeds = [int(v) for v in text.split(",")]
        else:
            seeds = list(range(int(text)))
    except ValueError:
        raise ValueError(allowed) from None
    if not seeds or min(seeds) < 0:
        raise ValueError(allowed)
    return seeds


def run_seed(seed: int, scenario: str, overrides: tuple[str, ...]) -> dict:
    """Fly ``scenario`` with ``seed``; its figures."""
    from scenarios import load_scenario
    from sim.evaluation.nav_baseline import DvlOnlyBaseline
    from sim.features import SeaTrialFeature
    from sim.mission import Mission
    from sim.outputs.trajectory_log import TrajectoryLog
    from sim.features.perception import world_model_metrics
    from sim.events.stage_timer import StageTimer

    scn = load_scenario(scenario, [*overrides, f"seed={seed}"])
    timer = StageTimer()
    log = TrajectoryLog()
    mission = Mission(scn, observers=[log], timer=timer)
    baseline = DvlOnlyBaseline(mission.parts.make_nav_filter)
    mission.observers.append(baseline)
    mission.reset()
    t0 = time.perf_counter()
    mission.run(progress=False)
    wall = time.perf_counter() - t0
    link = mission.feature(SeaTrialFeature).link
    onboard = mission.perception.world_model_metrics()
    surface = world_model_metrics(link.surface_world_model.world_model(), mission.perception.truth_targets)
    fused, dvl_only = baseline.mean_errors_m("survey")
    share = {name: sum(timer.seconds.get(s, 0.0) for s in stages) / wall
             for name, stages in (("link", LINK_STAGES), ("second_vehicle", VEHICLE_STAGES),
                                  ("surface_world_model", SURFACE_WM_STAGES))}
    link_metrics = link.metrics()
    nav = mission.nav_filter
    return {
        "seed": seed, "sim_time_s": mission.t_s, "wall_time_s": wall, "finished": mission.fsm.done,
        "onboard": {k: onboard[k] for k in ("matched", "missed", "false", "mean_position_error_m")},
        "surface": {k: surface[k] for k in ("matched", "missed", "false", "mean_position_error_m")},
        "nav_mean_error_survey_m": {"usbl_fused": fused, "dvl_only": dvl_only},
        "wall_time_share": share,
        "link": {"uplink": link_metrics["uplink_detections"], "downlink": link_metrics["downlink_usbl_fixes"],
                 "detections_queued": link_metrics["detections_queued"],
                 "detections_dropped_stale": link_metrics["detections_dropped_stale"],
                 "usbl_fixes_fused": nav.n_late_fused, "usbl_fixes_refused": nav.n_late_gated + nav.n_late_too_old},
        "contact": [list(p) for p in mission.physics.vehicles_in_contact()],
    }


def summarise(runs: list[dict]) -> dict:
    """Goal figures over the runs."""
    def mean(values):
        v = [x for x in values if x is not None and np.isfinite(x)]
        return float(np.mean(v)) if v else None

    diff = [r["surface"]["mean_position_error_m"] - r["onboard"]["mean_position_error_m"] for r in runs
            if r["surface"]["mean_position_error_m"] is not None and r["onboard"]["mean_position_error_m"] is not None]
    return {
        "runs": len(runs),
        "surface_all_six_found_runs": sum(r["surface"]["matched"] == 6 for r in runs),
        "surface_no_false_runs": sum(r["surface"]["false"] == 0 for r in runs),
        "surface_mean_false": mean([r["surface"]["false"] for r in runs]),
        "onboard_all_six_found_runs": sum(r["onboard"]["matched"] == 6 for r in runs),
        "onboard_no_false_runs": sum(r["onboard"]["false"] == 0 for r in runs),
        "surface_mean_error_m": mean([r["surface"]["mean_position_error_m"] for r in runs]),
        "onboard_mean_error_m": mean([r["onboard"]["mean_position_error_m"] for r in runs]),
        "surface_minus_onboard_error_m": {"mean": mean(diff), "max_abs": float(np.max(np.abs(diff))) if diff else None},
        "nav_mean_error_survey_m": {
            "usbl_fused": mean([r["nav_mean_error_survey_m"]["usbl_fused"] for r in runs]),
            "dvl_only": mean([r["nav_mean_error_survey_m"]["dvl_only"] for r in runs]),
            "fused_lower_runs": sum(r["nav_mean_error_survey_m"]["usbl_fused"] < r["nav_mean_error_survey_m"]["dvl_only"]
                                    for r in runs)},
        "wall_time_share": {k: mean([r["wall_time_share"][k] for r in runs])
                            for k in ("link", "second_vehicle", "surface_world_model")},
        "uplink_loss_rate": mean([r["link"]["uplink"]["lost"] / max(r["link"]["uplink"]["sent"], 1) for r in runs]),
        "uplink_mean_latency_s": mean([r["link"]["uplink"]["mean_latency_s"] for r in runs]),
        "uplink_p95_latency_s": mean([r["link"]["uplink"]["p95_latency_s"] for r in runs]),
        "downlink_loss_rate": mean([r["link"]["downlink"]["lost"] / max(r["link"]["downlink"]["sent"], 1)
                                    for r in runs]),
        "runs_with_contact": sum(bool(r["contact"]) for r in runs),
    }


def plot(runs: list[dict], path: Path) -> None:
    """Per seed: surface vs onboard world-model error, and the navigation error with and
    without the buoy's USBL fixes."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    seeds = [r["seed"] for r in runs]
    x = np.arange(len(runs))
    fig = Figure(figsize=(10, 3.8), layout="constrained")
    FigureCanvasAgg(fig)
    ax1, ax2 = fig.subplots(1, 2)
    w = 0.38
    nan = float("nan")
    ax1.bar(x - w / 2, [r["onboard"]["mean_position_error_m"] or nan for r in runs], w, label="onboard")
    ax1.bar(x + w / 2, [r["surface"]["mean_position_error_m"] or nan for r in runs], w, label="surface (over the link)")
    ax1.set(title="world model: mean OPI position error", xlabel="seed", ylabel="m", xticks=x, xticklabels=seeds)
    ax1.legend(fontsize=8)
    ax2.bar(x - w / 2, [r["nav_mean_error_survey_m"]["dvl_only"] for r in runs], w, label="DVL only")
    ax2.bar(x + w / 2, [r["nav_mean_error_survey_m"]["usbl_fused"] for r in runs], w, label="+ buoy USBL fixes")
    ax2.set(title="AUV navigation: mean horizontal error (survey)", xlabel="seed", ylabel="m", xticks=x,
            xticklabels=seeds)
    ax2.legend(fontsize=8)
    fig.savefig(path, dpi=110)


def _seed_job(job: tuple[int, str, tuple[str, ...]]) -> dict:
    return run_seed(*job)


def check_args(args) -> list[int]:
    """Refuse bad input before the first run: the seeds, the worker count, a scenario that
    loads with ``--set`` and flies the sea trial (the acoustic link and its surface vehicle),
    an output folder that can be written. Returns the seeds.

    Raises:
        CliError: naming the argument and what is allowed; ScenarioError: the scenario does
            not load.
    """
    try:
        seeds = parse_seeds(args.seeds)
    except ValueError as exc:
        raise CliError(str(exc)) from None
    if not 1 <= args.workers <= 2:
        raise CliError(f"--workers {args.workers}: allowed 1 or 2")
    scn = load_scenario(args.scenario, args.set)
    if not scn.comms.acoustic.enabled:
        raise CliError(f"--scenario {args.scenario}: does not fly the sea trial (comms.acoustic.enabled is false; "
                       "shipped: cssn_sea_trial)")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise CliError(f"--out {out}: is a file; give a folder for sea_trial_eval.json and .png")
    out.mkdir(parents=True, exist_ok=True)
    return seeds


def evaluate(args) -> int:
    seeds = check_args(args)
    out = Path(args.out)
    runs: list[dict] = []
    t0 = time.perf_counter()
    jobs = [(s, args.scenario, tuple(args.set)) for s in seeds]
    for k, r in enumerate(run_jobs(_seed_job, jobs, args.workers), 1):
        runs.append(r)
        n_true = r["surface"]["matched"] + r["surface"]["missed"]
        print(f"[{k}/{len(seeds)}] seed {r['seed']}: surface {r['surface']['matched']}/{n_true} "
              f"false {r['surface']['false']} err {r['surface']['mean_position_error_m']} m | onboard "
              f"{r['onboard']['matched']}/{n_true} false {r['onboard']['false']} err "
              f"{r['onboard']['mean_position_error_m']} m"
              f" | nav fused {r['nav_mean_error_survey_m']['usbl_fused']:.3f} m vs DVL-only "
              f"{r['nav_mean_error_survey_m']['dvl_only']:.3f} m | link {r['wall_time_share']['link']:.1%} "
              f"buoy {r['wall_time_share']['second_vehicle']:.1%} surface WM "
              f"{r['wall_time_share']['surface_world_model']:.1%} | {time.perf_counter() - t0:.0f} s elapsed",
              flush=True)
        runs.sort(key=lambda r: r["seed"])
        result = {"scenario": args.scenario, "overrides": args.set, "summary": summarise(runs), "runs": runs}
        (out / "sea_trial_eval.json").write_text(json.dumps(standard_json(result), indent=2) + "\n")
    plot(runs, out / "sea_trial_eval.png")
    print(json.dumps(standard_json(summarise(runs)), indent=2))
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = script_parser("evaluate_sea_trial.py", " ".join(__doc__.split("\n\n")[0].split()))
    ap.add_argument("--seeds", default="10", help="N (seeds 0..N-1), A-B, or a comma list (default 10)")
    ap.add_argument("--scenario", default="cssn_sea_trial", help="a scenario with the acoustic link and its buoy")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="scenario override")
    ap.add_argument("--workers", type=int, default=2, help="processes (at most 2 on a shared machine)")
    ap.add_argument("--out", required=True, help="folder for sea_trial_eval.json and .png")
    return run_script(ap, evaluate, argv)


if __name__ == "__main__":
    sys.exit(main())
