"""Seeded study of the target trackers (paper 004): fused vs sonar only vs USBL only.

Runs each tracking scenario over N seeds (no output files) and reports, per scenario, the
mean over seeds of each error set's mean and spread (m), the fraction of filter steps with a
sonar detection in the fused filter, the ROI gating of bubble clusters (counts, fractions and
their exact 95 % binomial intervals), and what the sonar
could see of the diver's bubble plume (breaths in its view, and apart from the diver's body
in its plane: ``TrackingEvaluation.plume_metrics``); with
``--json`` also every run's figures; with ``--png DIR`` the box plot of the four error sets
pooled over the seeds, horizontal error as in paper 004 fig. 8
(``DIR/tracking_study_<scenario>.png``).

    python scripts/tracking_study.py --seeds 20 --duration 150 --png runs/study \
        --scenarios track_static_vehicle track_moving_vehicle diver_follow
"""

from __future__ import annotations

import json
import logging
import math
import sys
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from scenarios.load import load_scenario  # noqa: E402
from sim.cli.app import run_script, script_parser  # noqa: E402
from sim.cli.args import positive_float, positive_int  # noqa: E402
from sim.cli.errors import CliError  # noqa: E402
from sim.evaluation.binomial_interval import proportion_ci95  # noqa: E402
from sim.evaluation.tracking_eval import ERROR_SETS, error_boxplot_png  # noqa: E402
from sim.features import TrackingFeature  # noqa: E402
from sim.mission import Mission  # noqa: E402
from sim.outputs.json_files import standard_json  # noqa: E402


def run_one(scenario: str, seed: int, duration_s: float | None,
            extra: list[str] = ()) -> tuple[dict, dict[str, np.ndarray]]:
    overrides = [f"seed={seed}"] + ([f"duration_s={duration_s}"] if duration_s else []) + list(extra)
    mission = Mission(load_scenario(scenario, overrides), perception=True)
    ev = mission.feature(TrackingFeature).observers({})[0]
    mission.observers.append(ev)
    mission.reset()
    while not mission.done:
        mission.step()
    return ev.metrics(), ev.error_sets(horizontal=True)


def summarise(runs: list[dict]) -> dict:
    out: dict = {"runs": len(runs)}
    for key, prefix in (("errors", ""), ("errors_horizontal", "horizontal_")):
        for k in ERROR_SETS:
            means = np.array([r[key][k].get("mean_m", math.nan) for r in runs], dtype=float)
            stds = np.array([r[key][k].get("std_m", math.nan) for r in runs], dtype=float)
            out[prefix + k] = {"mean_m": float(np.nanmean(means)), "spread_m": float(np.nanmean(stds)),
                               "mean_of_means_sd_m": float(np.nanstd(means))}
    for key in ("fused_sonar_step_fraction", "target_in_fov_fraction", "min_distance_m"):
        v = np.array([r[key] for r in runs], dtype=float)
        out[key] = {"mean": float(np.nanmean(v)), "min": float(np.nanmin(v)), "max": float(np.nanmax(v))}
    out["nees_horizontal"] = {m: {k: float(np.nanmean([r["nees_horizontal"][m][k] for r in runs]))
                                  for k in ("mean", "above_95_fraction")} for m in ("sonar", "usbl", "fused")}
    roi = {k: sum(r["roi"][k] for r in runs) for k in ("bubble_clusters", "bubble_rejected", "target_clusters",
                                                        "target_kept")}
    roi["bubble_rejected_ci95"] = proportion_ci95(roi["bubble_rejected"], roi["bubble_clusters"])
    roi["target_kept_ci95"] = proportion_ci95(roi["target_kept"], roi["target_clusters"])
    for frac, count in (("bubble_rejected_fraction", "bubble_clusters"), ("bubble_not_chosen_fraction", "bubble_clusters"),
                        ("target_kept_fraction", "target_clusters"), ("target_chosen_fraction", "target_clusters")):
        w = np.array([r["roi"][count] for r in runs], dtype=float)
        v = np.array([r["roi"][frac] if r["roi"][frac] is not None else math.nan for r in runs], dtype=float)
        ok = np.isfinite(v) & (w > 0)
        roi[frac] = float(np.sum(v[ok] * w[ok]) / np.sum(w[ok])) if ok.any() else math.nan
    out["roi"] = roi
    plumes = [r["plume"] for r in runs if r.get("plume", {}).get("frames")]
    if plumes:
        tot = {k: sum(p[k] for p in plumes) for k in ("frames", "breath_frames_in_view", "breath_frames_apart",
                                                      "breaths_seen")}
        seen = np.array([p["breaths_seen"] for p in plumes], dtype=float)
        age = np.array([p["last_in_view_age_mean_s"] for p in plumes], dtype=float)
        ok = np.isfinite(age) & (seen > 0)
        out["plume"] = {**tot, "apart_m": plumes[0]["apart_m"],
                        "breaths_in_view_per_frame": tot["breath_frames_in_view"] / tot["frames"],
                        "apart_fraction_of_in_view": tot["breath_frames_apart"] / tot["breath_frames_in_view"]
                        if tot["breath_frames_in_view"] else math.nan,
                        "last_in_view_age_mean_s": float(np.sum(age[ok] * seen[ok]) / np.sum(seen[ok]))
                        if ok.any() else math.nan,
                        "last_in_view_age_max_s": float(np.nanmax([p["last_in_view_age_max_s"] for p in plumes])),
                        "nearest_to_body_median_m_mean": float(np.nanmean(
                            [p["nearest_to_body_median_m"] for p in plumes]))}
    for prefix in ("", "horizontal_"):
        f, so, us = out[prefix + "fused"], out[prefix + "sonar"], out[prefix + "usbl"]
        out[prefix + "fused_beats_both"] = bool(f["mean_m"] < min(so["mean_m"], us["mean_m"]) and
                                                f["spread_m"] < min(so["spread_m"], us["spread_m"]))
    return out


def check_args(args) -> None:
    """Refuse bad input before the first run: every scenario loads and tracks a target, and
    the output paths can be written (a study's results are not lost at its end).

    Raises:
        CliError: naming the argument and what is allowed; ScenarioError: a scenario does not load.
    """
    for name in args.scenarios:
        scn = load_scenario(name, ([f"duration_s={args.duration}"] if args.duration else []) + args.overrides)
        if not scn.autonomy.tracking.enabled:
            raise CliError(f"--scenarios {name}: does not track a target (autonomy.tracking.enabled is false; "
                           "shipped: track_static_vehicle, track_moving_vehicle, diver_follow)")
    if args.png is not None:
        if args.png.exists() and not args.png.is_dir():
            raise CliError(f"--png {args.png}: is a file; give a folder for the box plots")
        args.png.mkdir(parents=True, exist_ok=True)
    if args.json is not None:
        if args.json.is_dir():
            raise CliError(f"--json {args.json}: is a folder; give a file name")
        if not args.json.parent.is_dir():
            raise CliError(f"--json {args.json}: folder {args.json.parent} does not exist")


def study(args) -> int:
    check_args(args)
    logging.getLogger("autonomy.tracking.tracker").setLevel(logging.ERROR)
    report = {}
    for name in args.scenarios:
        runs, pooled = [], {k: [] for k in ERROR_SETS}
        for seed in range(args.seeds):
            metrics, sets = run_one(name, seed, args.duration, args.overrides)
            runs.append(metrics)
            for k in ERROR_SETS:
                pooled[k].append(sets[k])
            e = runs[-1]["errors_horizontal"]
            print(f"{name} seed {seed} (horizontal): " + ", ".join(f"{k} {e[k].get('mean_m', math.nan):.2f}" for k in ERROR_SETS)
                  + f"; sonar steps {runs[-1]['fused_sonar_step_fraction']:.2f}"
                  + f"; fused NEES {runs[-1]['nees_horizontal']['fused']['mean']:.2f}"
                  + f"; bubble clusters {runs[-1]['roi']['bubble_clusters']}"
                  + f", breaths in view / apart {runs[-1].get('plume', {}).get('breath_frames_in_view', 0)}"
                  + f" / {runs[-1].get('plume', {}).get('breath_frames_apart', 0)}", flush=True)
        with warnings.catch_warnings():  # a set empty in every run (no breath in view) is NaN -> null
            warnings.simplefilter("ignore", RuntimeWarning)
            report[name] = standard_json({"summary": summarise(runs), "runs": runs})
        if args.png:
            stem = Path(name).stem
            error_boxplot_png({k: np.concatenate(v) for k, v in pooled.items()}, args.png / f"tracking_study_{stem}.png",
                              f"{stem}: {args.seeds} seeds", ylabel="horizontal position error (m)")
        print(json.dumps({name: report[name]["summary"]}, indent=1), flush=True)
    if args.json:
        args.json.write_text(json.dumps(report, indent=1))
    return 0


def main(argv: list[str] | None = None) -> int:
    p = script_parser("tracking_study.py", __doc__.splitlines()[0])
    p.add_argument("--seeds", type=positive_int, default=20, help="run seeds 0 to N-1 (default 20)")
    p.add_argument("--duration", type=positive_float, default=None, help="override duration_s (s)")
    p.add_argument("--scenarios", nargs="+", default=["track_static_vehicle", "track_moving_vehicle"],
                   help="shipped scenario names or YAML files that track a target")
    p.add_argument("--json", type=Path, default=None, help="write every run and the summary here")
    p.add_argument("--png", type=Path, default=None, help="folder for the pooled box plots")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="scenario override for every run (as `auvsim run --set`), e.g. "
                        "world.current.velocity_ned_mps=[-0.35,0.35,0]")
    return run_script(p, study, argv)


if __name__ == "__main__":
    raise SystemExit(main())
