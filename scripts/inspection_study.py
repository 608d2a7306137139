"""Active inspection against the lawnmower over seeds and layouts (the figures of docs/studies/inspection.md).

For each layout and seed it flies the shipped lawnmower, then the same world with
``autonomy.guidance.inspection`` on (``coverage_then_inspect``), and, with ``--equal-time``,
inspection that keeps looking until the lawnmower's mission time. It prints one line per run
and a table per layout: mission time, targets found / missed, false objects, mean position
error of the matched targets, class accuracy of the matched true objects (targets and
distractors), inspection legs aimed at objects that end up false, and the planner's re-plan
cost (p99 over every re-plan of the run).

    python scripts/inspection_study.py --nav truth --seeds 0-4 --jobs 2 --json runs/insp_truth.json
    python scripts/inspection_study.py --nav truth --layout mixed_targets_rough --equal-time --seeds 0-4 --jobs 2
    python scripts/inspection_study.py --tabulate docs/studies/inspection_study.json   # the shipped figures' runs

Layouts: ``cssn`` (cssn_lawnmower's world), ``mixed3``, ``mixed8``, ``mixed12``
(scripts/world_model_layouts/) and any shipped scenario name or YAML path.
"""

from __future__ import annotations

import argparse
import difflib
import json
import os
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
    """``0-4`` or ``0,2,5`` -> the seeds; ValueError (its message says what is wrong) when
    malformed, empty or a range runs backwards."""
    malformed = "expected e.g. 0-4 or 0,2,5"
    out: list[int] = []
    for part in text.split(","):
        try:
            ends = [int(v) for v in part.split("-")] if "-" in part else [int(part)] * 2
        except ValueError:
            raise ValueError(malformed) from None
        if len(ends) != 2:
            raise ValueError(malformed)
        if ends[1] < ends[0]:
            raise ValueError(f"the range {part} runs backwards; write {ends[1]}-{ends[0]}")
        out += list(range(ends[0], ends[1] + 1))
    if not out:
        raise ValueError(malformed)
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
        out.update(legs_sent=ins["legs_sent"], legs_started=ins["legs_started"], legs_completed=ins["legs_completed"],
                   legs_at_false_objects=ins["legs_at_false_objects"],
                   time_to_confident_map_s=ins["time_to_confident_map_s"], end_reason=ins["end_reason"])
    mission.close()
    return out


RUN_KEYS = ("layout", "seed", "variant", "mission_time_s")


def _read_runs(path: Path, flag: str) -> list[dict] | str:
    """The runs of a study's ``--json`` file, or a one-line reason it is not one."""
    try:
        rows = json.loads(path.read_text())
    except OSError as exc:
        return f"{flag} {path}: cannot read it ({exc.strerror or exc})"
    except ValueError:
        return f"{flag} {path}: not JSON; give a file written by this script's --json"
    if not isinstance(rows, list) or not rows or not all(isinstance(r, dict) and all(k in r for k in RUN_KEYS)
                                                         for r in rows):
        return f"{flag} {path}: not a file of runs written by this script's --json (a non-empty list of runs)"
    return rows


def _table(rows: list[dict]) -> list[str]:
    """Per layout and navigation source: one row per variant, summed or averaged over seeds."""
    lines = []
    head = (f"  {'variant':<11} {'time s':>7} {'ratio':>6} {'found':>8} {'false':>6} {'mean err m':>11} "
            f"{'class acc':>10} {'legs sent':>10} {'at false':>9}")
    for layout, nav in dict.fromkeys((r["layout"], r.get("nav_source", "estimate")) for r in rows):
        here = [r for r in rows if r["layout"] == layout and r.get("nav_source", "estimate") == nav]
        lines += [f"\n{layout} (nav: {nav}, {len({r['seed'] for r in here})} seeds)", head]
        base = {r["seed"]: r for r in here if r["variant"] == "lawnmower"}
        for variant in dict.fromkeys(r["variant"] for r in here):
            rs = [r for r in here if r["variant"] == variant]
            t = np.mean([r["mission_time_s"] for r in rs])
            errs = [r["mean_error_m"] for r in rs if r["mean_error_m"] is not None]
            acc = sum(r["class_right"] for r in rs) / max(sum(r["class_matched"] for r in rs), 1)
            paired = [base[r["seed"]]["mission_time_s"] for r in rs if r["seed"] in base]
            ratio = f"{t / np.mean(paired):.2f}x" if paired and variant != "lawnmower" else "-"
            found = f"{sum(r['matched'] for r in rs)}/{sum(r['matched'] + r['missed'] for r in rs)}"
            legs = "-" if variant == "lawnmower" else str(sum(r.get("legs_sent", 0) for r in rs))
            at_false = "-" if variant == "lawnmower" else str(sum(r.get("legs_at_false_objects", 0) for r in rs))
            err = f"{np.mean(errs):.3f}" if errs else "n/a"
            lines.append(f"  {variant:<11} {t:7.0f} {ratio:>6} {found:>8} {sum(r['false'] for r in rs):6d} {err:>11} "
                         f"{acc:10.3f} {legs:>10} {at_false:>9}")
    return lines


def _progress(r: dict) -> str:
    err = "n/a" if r["mean_error_m"] is None else f"{r['mean_error_m']:.3f} m"
    return (f"{r['layout']} seed {r['seed']} {r['variant']}: {r['mission_time_s']:.0f} s, {r['matched']}/"
            f"{r['matched'] + r['missed']} found, {r['false']} false, mean error {err}")


def plot(rows: list[dict], path: Path) -> None:
    """Mission time against mean position error, one point per run, one panel per layout and
    navigation source (the lawnmower's runs and the inspection's of the same seeds)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    layouts = list(dict.fromkeys(r["layout"] for r in rows))
    navs = list(dict.fromkeys(r.get("nav_source", "estimate") for r in rows))
    fig = Figure(figsize=(3.0 * len(layouts), 2.8 * len(navs)), layout="constrained")
    FigureCanvasAgg(fig)
    grid = fig.subplots(len(navs), len(layouts), squeeze=False)
    axes = [grid[i, j] for i in range(len(navs)) for j in range(len(layouts))]
    panels = [(layout, nav) for nav in navs for layout in layouts]
    style = {"lawnmower": ("tab:blue", "s"), "inspect": ("tab:red", "o"), "equal_time": ("tab:purple", "^")}
    for ax, (layout, nav) in zip(axes, panels):
        if not any(r["layout"] == layout and r.get("nav_source", "estimate") == nav for r in rows):
            ax.set_axis_off()  # this layout was not flown with this pose
            continue
        for variant, (color, marker) in style.items():
            rs = [r for r in rows if r["layout"] == layout and r.get("nav_source", "estimate") == nav
                  and r["variant"] == variant and r["mean_error_m"] is not None]
            if rs:
                ax.scatter([r["mission_time_s"] for r in rs], [r["mean_error_m"] for r in rs], c=color, marker=marker,
                           s=22, label=variant.replace("_", " "))
        ax.set_title(f"{layout} (nav: {nav})", fontsize=9)
        ax.set_xlabel("mission time (s)")
        ax.set_ylim(bottom=0.0)
        ax.grid(alpha=0.3)
    for i in range(len(navs)):
        grid[i, 0].set_ylabel("mean target position error (m)", fontsize=8)
    seen: dict[str, object] = {}
    for ax in axes:  # one legend for every variant drawn in any panel
        for h, lab in zip(*ax.get_legend_handles_labels()):
            seen.setdefault(lab, h)
    axes[0].legend(list(seen.values()), list(seen), fontsize=7)
    fig.savefig(path, dpi=110)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--layout", action="append", help="cssn, mixed3, mixed8, mixed12 or a scenario (repeatable; "
                    "default: the four)")
    ap.add_argument("--seeds", default="0-4", help="e.g. 0-4 or 0,2,5 (default 0-4)")
    ap.add_argument("--equal-time", action="store_true", help="also inspect until the lawnmower's mission time")
    ap.add_argument("--no-inspect", action="store_true", help="with --equal-time: skip the finish-when-confident runs")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="override for the inspection runs only (repeatable), e.g. "
                         "autonomy.guidance.inspection.look_2sigma_m=0.3")
    ap.add_argument("--lawnmower-json", type=Path, help="take the lawnmower runs from an earlier --json instead")
    ap.add_argument("--nav", choices=("estimate", "truth"), default="estimate",
                    help="pose for geolocalisation: estimate (the navigation filter's; its error dominates the map's) "
                         "or truth (paper 000's simulated evaluation: the map's own error)")
    ap.add_argument("--jobs", type=int, default=1, help="processes, at most the cores (default 1)")
    ap.add_argument("--json", type=Path, help="write every run's figures here")
    ap.add_argument("--png", type=Path, help="plot mission time against mean error per run here")
    ap.add_argument("--tabulate", type=Path, nargs="+", metavar="JSON",
                    help="run nothing: print the tables (and --png) of earlier --json files")
    a = ap.parse_args(argv)
    for flag, path in (("--json", a.json), ("--png", a.png)):
        if path is not None and not path.resolve().parent.is_dir():
            print(f"{flag} {path}: its folder does not exist", file=sys.stderr)
            return 2
        if path is not None and path.is_dir():
            print(f"{flag} {path}: is a folder; give a file name", file=sys.stderr)
            return 2
    if a.no_inspect and not a.equal_time:
        print("--no-inspect: only with --equal-time (it skips the finish-when-confident runs of that study)",
              file=sys.stderr)
        return 2
    if a.tabulate:
        rows = []
        for f in a.tabulate:
            read = _read_runs(f, "--tabulate")
            if isinstance(read, str):
                print(read, file=sys.stderr)
                return 2
            rows += read
        print("\n".join(_table(rows)))
        if a.png:
            plot(rows, a.png)
        return 0
    layouts = a.layout or list(LAYOUTS)
    try:
        seeds = _seeds(a.seeds)
    except ValueError as exc:
        print(f"--seeds {a.seeds!r}: {exc}", file=sys.stderr)
        return 2
    cores = os.cpu_count() or 1
    if not 1 <= a.jobs <= cores:
        print(f"--jobs: 1 to {cores} (the cores here), got {a.jobs}", file=sys.stderr)
        return 2
    from scenarios import load_scenario
    from scenarios.load import ScenarioError, resolve_path, scenarios_dir

    for layout in layouts:
        if layout not in LAYOUTS:
            try:
                resolve_path(layout)
            except (FileNotFoundError, ScenarioError):
                shipped = sorted(f.stem for f in scenarios_dir().glob("*.yaml"))
                close = difflib.get_close_matches(layout, [*LAYOUTS, *shipped], n=1)
                hint = f"; did you mean {close[0]}?" if close else ""
                print(f"--layout {layout}: neither a layout of this study ({', '.join(LAYOUTS)}) nor a shipped "
                      f"scenario or scenario file{hint}", file=sys.stderr)
                return 2
        try:  # the inspection runs' overrides, checked before any mission flies
            load_scenario(LAYOUTS.get(layout, layout), ["autonomy.guidance.inspection.enabled=true", *a.set])
        except (FileNotFoundError, ScenarioError, ValueError) as exc:
            where = f"--layout {layout} with --set" if a.set else f"--layout {layout}"
            print(f"{where}: {str(exc).splitlines()[0]}", file=sys.stderr)
            return 2
    rows: list[dict] = []
    extra = tuple(a.set)
    if a.lawnmower_json:
        read = _read_runs(a.lawnmower_json, "--lawnmower-json")
        if isinstance(read, str):
            print(read, file=sys.stderr)
            return 2
        rows = [r for r in read if r["variant"] == "lawnmower"
                and r.get("nav_source") == a.nav and r["layout"] in layouts and r["seed"] in seeds]
        missing = sorted({(lay, s) for lay in layouts for s in seeds} - {(r["layout"], r["seed"]) for r in rows})
        if missing:
            print(f"--lawnmower-json {a.lawnmower_json}: no lawnmower run (nav {a.nav}) for "
                  f"{', '.join(f'{lay} seed {s}' for lay, s in missing)}; flying those", file=sys.stderr)
    with ProcessPoolExecutor(max_workers=a.jobs) as pool:
        have = {(r["layout"], r["seed"]) for r in rows}
        first = [(lay, s, "lawnmower", None, (), a.nav) for lay in layouts for s in seeds if (lay, s) not in have]
        if not (a.equal_time and a.no_inspect):
            first += [(lay, s, "inspect", None, extra, a.nav) for lay in layouts for s in seeds]
        for r in pool.map(run_one, first):
            print(_progress(r), flush=True)
            rows.append(r)
        if a.equal_time:
            base = {(r["layout"], r["seed"]): r["mission_time_s"] for r in rows if r["variant"] == "lawnmower"}
            for r in pool.map(run_one, [(lay, s, "equal_time", base[(lay, s)], extra, a.nav) for lay in layouts for s in seeds]):
                print(_progress(r), flush=True)
                rows.append(r)
    print("\n".join(_table(rows)))
    if a.json:
        a.json.write_text(json.dumps(rows, indent=1))
    if a.png:
        plot(rows, a.png)
    return 0


if __name__ == "__main__":
    sys.exit(main())
