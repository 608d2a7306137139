"""Active inspection against the lawnmower over seeds and layouts (the figures of docs/studies/inspection.md).

For each layout and seed it flies the shipped lawnmower, then the same world with
``autonomy.guidance.inspection`` on (``coverage_then_inspect``), and, with ``--equal-time``,
inspection that keeps looking until the lawnmower's mission time. It prints one line per run
and a table per layout: mission time, targets found / missed, false objects, mean position
error of the matched targets, class accuracy of the matched true objects (targets and
distractors), inspection legs aimed at objects that end up false, and the planner's re-plan
cost (p99 over every re-plan of the run).

    python scripts/inspection_study.py --seeds 0-4 --jobs 2 --json docs/studies/inspection_study.json
    python scripts/inspection_study.py --layout mixed_targets_rough --equal-time --seeds 0-4 --jobs 2

Layouts: ``cssn`` (cssn_lawnmower's world), ``mixed3``, ``mixed8``, ``mixed12``
(scripts/world_model_layouts/) and any shipped scenario name or YAML path.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
LAYOUTS = {"cssn": "cssn_lawnmower", "mixed3": str(HERE / "world_model_layouts" / "mixed3.yaml"),
           "mixed8": str(HERE / "world_model_layouts" / "mixed8.yaml"),
           "mixed12": str(HERE / "world_model_layouts" / "mixed12.yaml")}
MATCH_RADIUS_M = 2.0


def _seeds(text: str) -> list[int]:
    out: list[int] = []
    for part in text.split(","):
        if "-" in part:
            a, b = part.split("-")
            out += list(range(int(a), int(b) + 1))
        else:
            out.append(int(part))
    return out


def class_accuracy(objects, scene_objects) -> tuple[int, int]:
    """(right, matched): true objects (targets and distractors) matched by a world-model object
    within ``MATCH_RADIUS_M`` (optimal assignment) whose class (target or not) the model has right."""
    from scipy.optimize import linear_sum_assignment

    truth = [(np.asarray(o.pos_ned, dtype=float), bool(o.is_target)) for o in scene_objects]
    if not truth or not objects:
        return 0, 0
    est = np.array([np.asarray(o.pos_ned, dtype=float)[:2] for o in objects])
    tru = np.array([p[:2] for p, _ in truth])
    d = np.linalg.norm(est[:, None] - tru[None], axis=2)
    rows, cols = linear_sum_assignment(np.where(d <= MATCH_RADIUS_M, d, 1e6))
    right = matched = 0
    for i, j in zip(rows, cols):
        if d[i, j] <= MATCH_RADIUS_M:
            matched += 1
            right += int((objects[i].class_name == "target") == truth[j][1])
    return right, matched


def run_one(args: tuple[str, int, str, float | None, tuple[str, ...], str]) -> dict:
    """One mission: (layout, seed, variant, time budget s or None, inspection overrides, nav source)
    -> its figures."""
    layout, seed, variant, budget, extra, nav_source = args
    from scenarios import load_scenario
    from sim.features.inspection import InspectionFeature
    from sim.mission import Mission

    sets = [f"seed={seed}"]
    if variant != "lawnmower":
        sets.append("autonomy.guidance.inspection.enabled=true")
        sets += list(extra)
    if variant == "equal_time":
        sets += ["autonomy.guidance.inspection.finish_when_confident=false",
                 "autonomy.guidance.inspection.max_legs_per_object=20",
                 f"autonomy.guidance.inspection.time_budget_s={budget}"]
    scenario = load_scenario(LAYOUTS.get(layout, layout), sets)
    mission = Mission(scenario, nav_source=nav_source)
    wall0 = time.process_time()
    summary = mission.run(progress=False)
    perception = mission.perception
    wm = perception.world_model_metrics()
    right, matched = class_accuracy(perception.world_objects(), scenario.world.targets)
    out = dict(layout=layout, seed=seed, variant=variant, nav_source=nav_source, mission_time_s=round(summary.sim_time_s, 1),
               finished=bool(summary.finished), aborted=bool(summary.aborted), objects=wm["objects"],
               matched=wm["matched"], missed=wm["missed"], false=wm["false"],
               mean_error_m=wm["mean_position_error_m"], class_right=right, class_matched=matched,
               cpu_s=round(time.process_time() - wall0, 1))
    feature = mission.feature(InspectionFeature)
    if feature is not None:
        metrics: dict = {}
        feature.add_metrics(metrics, None)
        ins = metrics["inspection"]
        out.update(legs_sent=ins["legs_sent"], legs_flown=ins["legs_flown"],
                   legs_at_false_objects=ins["legs_at_false_objects"],
                   time_to_confident_map_s=ins["time_to_confident_map_s"], end_reason=ins["end_reason"])
    mission.close()
    return out


def _table(rows: list[dict]) -> list[str]:
    lines = []
    for layout in dict.fromkeys(r["layout"] for r in rows):
        lines.append(f"\n{layout}")
        lines.append("  variant      time s   found/targets  false  mean err m  class acc  false legs  legs")
        base = {r["seed"]: r for r in rows if r["layout"] == layout and r["variant"] == "lawnmower"}
        for variant in dict.fromkeys(r["variant"] for r in rows if r["layout"] == layout):
            rs = [r for r in rows if r["layout"] == layout and r["variant"] == variant]
            t = np.mean([r["mission_time_s"] for r in rs])
            errs = [r["mean_error_m"] for r in rs if r["mean_error_m"] is not None]
            acc = sum(r["class_right"] for r in rs) / max(sum(r["class_matched"] for r in rs), 1)
            ratio = (f" ({t / np.mean([base[r['seed']]['mission_time_s'] for r in rs if r['seed'] in base]):.2f}x)"
                     if base and variant != "lawnmower" else "")
            lines.append(
                f"  {variant:<12} {t:6.0f}{ratio:<8} {sum(r['matched'] for r in rs):3d}/"
                f"{sum(r['matched'] + r['missed'] for r in rs):<3d}        {sum(r['false'] for r in rs):3d}"
                f"    {np.mean(errs) if errs else float('nan'):.3f}      {acc:.3f}     "
                f"{sum(r.get('legs_at_false_objects', 0) for r in rs):3d}        {sum(r.get('legs_flown', 0) for r in rs)}")
    return lines


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--layout", action="append", help="cssn, mixed3, mixed8, mixed12 or a scenario (repeatable; "
                    "default: the four)")
    ap.add_argument("--seeds", default="0-4", help="e.g. 0-4 or 0,2,5")
    ap.add_argument("--equal-time", action="store_true", help="also inspect until the lawnmower's mission time")
    ap.add_argument("--no-inspect", action="store_true", help="with --equal-time: skip the finish-when-confident runs")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="override for the inspection runs only (repeatable), e.g. "
                         "autonomy.guidance.inspection.look_2sigma_m=0.3")
    ap.add_argument("--lawnmower-json", type=Path, help="take the lawnmower runs from an earlier --json instead")
    ap.add_argument("--nav", choices=("estimate", "truth"), default="estimate",
                    help="pose for geolocalisation: estimate (the navigation filter's; its error dominates the map's) "
                         "or truth (paper 000's simulated evaluation: the map's own error)")
    ap.add_argument("--jobs", type=int, default=1, help="processes (at most the cores)")
    ap.add_argument("--json", type=Path, help="write every run's figures here")
    a = ap.parse_args(argv)
    layouts = a.layout or list(LAYOUTS)
    try:
        seeds = _seeds(a.seeds)
    except ValueError:
        print(f"--seeds: expected e.g. 0-4 or 0,2,5, got {a.seeds!r}", file=sys.stderr)
        return 2
    if a.jobs < 1:
        print(f"--jobs: must be >= 1, got {a.jobs}", file=sys.stderr)
        return 2
    from scenarios.load import resolve_path

    for layout in layouts:
        if layout not in LAYOUTS:
            try:
                resolve_path(layout)
            except (FileNotFoundError, ValueError) as exc:
                print(f"--layout: {exc}", file=sys.stderr)
                return 2
    rows: list[dict] = []
    extra = tuple(a.set)
    if a.lawnmower_json:
        rows = [r for r in json.loads(a.lawnmower_json.read_text()) if r["variant"] == "lawnmower"
                and r.get("nav_source") == a.nav and r["layout"] in layouts and r["seed"] in seeds]
    with ProcessPoolExecutor(max_workers=a.jobs) as pool:
        have = {(r["layout"], r["seed"]) for r in rows}
        first = [(lay, s, "lawnmower", None, (), a.nav) for lay in layouts for s in seeds if (lay, s) not in have]
        if not (a.equal_time and a.no_inspect):
            first += [(lay, s, "inspect", None, extra, a.nav) for lay in layouts for s in seeds]
        for r in pool.map(run_one, first):
            print(json.dumps(r), flush=True)
            rows.append(r)
        if a.equal_time:
            base = {(r["layout"], r["seed"]): r["mission_time_s"] for r in rows if r["variant"] == "lawnmower"}
            for r in pool.map(run_one, [(lay, s, "equal_time", base[(lay, s)], extra, a.nav) for lay in layouts for s in seeds]):
                print(json.dumps(r), flush=True)
                rows.append(r)
    print("\n".join(_table(rows)))
    if a.json:
        a.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
