"""``auvsim run``: fly a mission and write its results into an output directory.

Results are written into a hidden ``.<name>.partial`` directory next to ``--out`` and moved
into place only when complete, so a failed or interrupted run never leaves half-written
results that look finished.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
from pathlib import Path
from typing import Any

import numpy as np

from scenarios.load import load_scenario
from scenarios.schema import Scenario
from sim.map_plot import plot_map
from sim.mission import Mission
from sim.trajectory_log import TrajectoryLog


class OutputDirError(Exception):
    pass


def _json_default(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (np.floating, np.integer)):
        return obj.item()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def _clean(obj: Any) -> Any:
    """Replace NaN/inf by None so the JSON is standard."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    return obj


def write_json(path: Path, data: Any) -> None:
    path.write_text(json.dumps(_clean(json.loads(json.dumps(data, default=_json_default))), indent=2) + "\n")


def collect_metrics(mission: Mission, log: TrajectoryLog) -> dict[str, Any]:
    s = mission.summary()
    metrics: dict[str, Any] = {
        "scenario": mission.scenario.name,
        "seed": mission.seed,
        "nav_source": mission.nav_source,
        "sim_time_s": s.sim_time_s,
        "wall_time_s": s.wall_time_s,
        "real_time_factor": s.sim_time_s / s.wall_time_s if s.wall_time_s > 0 else None,
        "distance_travelled_m": log.distance_travelled_m(),
        "mission": {"finished": s.finished, "aborted": s.aborted, "abort_reason": s.abort_reason,
                    "final_mode": mission.fsm.mode},
        "navigation": log.navigation_metrics(),
        "perception": {"fls_frames": mission.n_fls_frames},
    }
    if mission.perception is not None:
        metrics["perception"].update(mission.perception.detection_metrics())
        metrics["world_model"] = mission.perception.world_model_metrics()
    return metrics


def run_mission(
    scenario: Scenario, out: Path, *, nav_source: str = "estimate", rerun: bool = True,
    progress: bool = True, overwrite: bool = False,
) -> dict[str, Any]:
    """Run ``scenario`` and write metrics.json, trajectory.csv, world_model.json, map.png
    (and recording.rrd) into ``out``. Returns the metrics."""
    out = Path(out)
    if out.exists() and any(out.iterdir()) and not overwrite:
        raise OutputDirError(f"{out}: output directory exists and is not empty (choose another --out, or pass --overwrite)")
    partial = out.parent / f".{out.name}.partial"
    if partial.exists():
        shutil.rmtree(partial)
    partial.mkdir(parents=True)
    (partial / "INCOMPLETE").write_text("this run did not finish; results here are not valid\n")

    log = TrajectoryLog()
    observers: list[Any] = [log]
    if rerun:
        from sim.rerun_recording import RerunRecorder

        observers.append(RerunRecorder(partial / "recording.rrd"))
    mission = Mission(scenario, nav_source=nav_source, observers=observers)
    mission.reset()
    mission.run(progress=progress)

    metrics = collect_metrics(mission, log)
    log.write_csv(partial / "trajectory.csv")
    estimates, rejected = [], []
    if mission.perception is not None:
        write_json(partial / "world_model.json", mission.perception.world_model_json())
        targets = mission.perception.target_objects()
        estimates = [(f"{o.id}", o.pos_ned, o.cov_ned) for o in targets]
        target_ids = {o.id for o in targets}
        rejected = [o.pos_ned for o in mission.perception.world_objects() if o.id not in target_ids]
    plot_map(
        partial / "map.png",
        true_pos_ned=log.true_pos_ned, est_pos_ned=log.est_pos_ned, waypoints_ne=mission.waypoints_ne,
        targets=[(o.name, o.centroid_ned, o.is_target) for o in mission.world.objects],
        estimates=estimates, rejected_ned=rejected,
        title=f"{scenario.name} seed {mission.seed} (nav: {nav_source})",
    )
    write_json(partial / "metrics.json", metrics)
    (partial / "INCOMPLETE").unlink()
    if out.exists():
        shutil.rmtree(out)
    os.replace(partial, out)
    return metrics


def run_mission_command(args: argparse.Namespace) -> int:
    from sim.cli import CliError

    overrides = list(args.overrides)
    if args.seed is not None:
        overrides.append(f"seed={args.seed}")
    if args.detector is not None:
        overrides.append(f"autonomy.atr.detector={args.detector}")
    scenario = load_scenario(args.scenario, overrides)
    try:
        metrics = run_mission(scenario, Path(args.out), nav_source=args.nav, rerun=not args.no_rerun,
                              overwrite=getattr(args, "overwrite", False))
    except OutputDirError as exc:
        raise CliError(str(exc)) from None
    nav = metrics["navigation"]
    print(f"sim {metrics['sim_time_s']:.0f} s in {metrics['wall_time_s']:.1f} s wall "
          f"({metrics['real_time_factor']:.1f}x real time), {metrics['distance_travelled_m']:.0f} m travelled, "
          f"final nav error {nav['final_position_error_m']:.2f} m")
    if "world_model" in metrics:
        wm = metrics["world_model"]
        print(f"world model: {wm['objects']} objects, {wm['matched']} matched, {wm['missed']} missed, "
              f"{wm['false']} false, mean error {wm['mean_position_error_m']} m, GOSPA {wm['gospa']}")
    print(f"results in {args.out}")
    return 0
