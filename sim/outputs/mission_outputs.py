"""Fly a mission and write its results into a run folder.

Results are written into a hidden ``.<name>.partial`` folder next to the output folder and
moved into place only when complete (:class:`sim.outputs.run_dir.StagedOutput`), so a
failed or interrupted run never leaves half-written results that look finished, and an
earlier run being replaced is removed only once the new one is in place.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from autonomy.geodesy import GeodeticOrigin, ned_to_lat_lon_depth
from scenarios.schema import Scenario
from sim.outputs.map_plot import plot_map
from sim.evaluation.detection_scoring import DetectionScorer
from sim.perception import target_objects, world_model_metrics
from sim.mission import Mission
from sim.movers import BUBBLE_CLASS
from sim.outputs.progress import MissionProgress
from sim.outputs.run_dir import StagedOutput, check_output_dir
from sim.outputs.trajectory_log import TrajectoryLog

METRICS_DECIMALS = 4


def _json_default(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (np.floating, np.integer, np.bool_)):
        return obj.item()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def _clean(obj: Any, decimals: int | None) -> Any:
    """NaN/inf -> None (standard JSON); floats rounded to ``decimals`` when given."""
    if isinstance(obj, float):
        if not math.isfinite(obj):
            return None
        return round(obj, decimals) if decimals is not None else obj
    if isinstance(obj, dict):
        return {k: _clean(v, decimals) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v, decimals) for v in obj]
    return obj


def standard_json(data: Any, decimals: int | None = None) -> Any:
    """``data`` as plain JSON values (numpy converted, NaN/inf -> None, which ``json`` would
    write as the non-standard ``NaN``), floats rounded to ``decimals`` when given."""
    return _clean(json.loads(json.dumps(data, default=_json_default)), decimals)


def write_json(path: Path, data: Any, decimals: int | None = None) -> None:
    """Write ``data`` as indented standard JSON (NaN -> null), floats rounded to ``decimals``."""
    path.write_text(json.dumps(standard_json(data, decimals), indent=2) + "\n")


def with_geodetic(world_model: dict[str, Any], origin: GeodeticOrigin) -> dict[str, Any]:
    """A world model's JSON (:meth:`autonomy.world_model.PMHA.to_json`) with each object's
    ``lat_deg``, ``lon_deg`` and ``depth_m`` (below the origin's height) beside its
    ``pos_ned`` (paper 000 section VII reports objects in latitude / longitude / depth)."""
    out = dict(world_model)
    out["origin"] = origin.model_dump()
    objects = []
    for obj in world_model.get("objects", []):
        lat, lon, depth = (float(v) for v in ned_to_lat_lon_depth(obj["pos_ned"], origin))
        objects.append({**obj, "lat_deg": lat, "lon_deg": lon, "depth_m": depth})
    out["objects"] = objects
    return out


def planned_length_s(mission: Mission) -> float:
    """Planned mission length, s: start delay plus the survey path at the survey speed.

    Used as the 100 % of the progress display; capped by the scenario's duration (a buddy
    mission, which flies no survey: the duration).
    """
    scn = mission.scenario
    if scn.autonomy.guidance.buddy.enabled:  # no survey plan: the mission runs to duration_s
        return float(scn.duration_s)
    survey = scn.autonomy.guidance.survey
    wps = np.asarray(mission.waypoints_ne, dtype=float).reshape(-1, 2)
    start = np.asarray(scn.vehicle.initial_pos_ned[:2], dtype=float)
    path_m = float(np.linalg.norm(wps[0] - start) + np.linalg.norm(np.diff(wps, axis=0), axis=1).sum()) \
        if len(wps) else 0.0
    # Turns, the dive and the approach to each leg take about a tenth longer than the straight path.
    planned = scn.autonomy.guidance.mission.start_delay_s + 1.1 * path_m / max(survey.speed_mps, 1e-6)
    return float(min(planned, scn.duration_s))


def perception_counts(mission: Mission) -> dict[str, Any]:
    """Which sonar perception read and the frames of each forward-looking sonar:
    ``fls_frames`` (all sonars together), ``fls_frames_by_sensor`` (name -> frames),
    ``sonar`` (the entry perception or the tracker read, None without one; chosen by
    ``autonomy.atr.sonar_sensor``, or ``autonomy.tracking.sonar_sensor`` when tracking) and
    ``sonar_frames`` (its frames); with other sonars, a ``note`` that they were not processed."""
    by_sensor = mission.fls_frames_by_sensor
    sonar = mission.fls.name if mission.fls is not None else None
    out: dict[str, Any] = {"fls_frames": sum(by_sensor.values()), "fls_frames_by_sensor": by_sensor,
                           "sonar": sonar, "sonar_frames": by_sensor.get(sonar, 0) if sonar is not None else 0}
    others = [n for n in by_sensor if n != sonar]
    if others:
        used = f"perception read sensors.{sonar}" if sonar is not None else "no perception ran"
        out["note"] = (f"{used}; {', '.join(f'sensors.{n}' for n in others)} rendered and recorded, not processed "
                       "(choose the sonar with autonomy.atr.sonar_sensor)")
    return out


def collect_metrics(mission: Mission, log: TrajectoryLog, scorer: DetectionScorer | None = None) -> dict[str, Any]:
    """The figures of a finished mission (navigation, detections as ``scorer`` counted them,
    world model)."""
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
        "perception": perception_counts(mission),
    }
    if mission.perception is not None:
        if scorer is not None:
            metrics["perception"].update(scorer.metrics())
        wm = mission.perception.world_model_metrics()
        n_all = len(mission.perception.world_objects())
        n_targets = n_all - int(wm.get("objects_not_target", 0))
        wm["world_model_json_objects"] = n_all
        wm["note"] = (f"world_model.json holds all {n_all} objects the world model keeps; {n_targets} it classifies "
                      f"as targets are scored against the true targets (objects, matched, missed, false); "
                      f"{n_all - n_targets} it classifies as not targets (rocks, clutter) are listed there "
                      "but not scored")
        metrics["world_model"] = wm
    others = log.other_paths_ned()
    if others:
        t_auv, p_auv, t_others = log.t_s, log.true_pos_ned, log.other_paths_t_s()
        auv = np.column_stack([np.interp(t_others, t_auv, p_auv[:, k]) for k in range(3)])
        metrics["vehicles"] = {
            "contact_periods": {"-".join(pair): n for pair, n in mission.vehicle_contacts.items()},
            "min_separation_m": {name: float(np.min(np.linalg.norm(path - auv, axis=1))) for name, path in others.items()},
            "note": "contact periods: autonomy periods ending with hulls touching (every period checked); "
                    "least separation of the body origins, sampled once a second",
        }
    if mission.link is not None:
        metrics["link"] = mission.link.metrics()
        nav = mission.nav_filter
        if hasattr(nav, "n_late_fused"):
            metrics["link"]["usbl_fixes_fused"] = nav.n_late_fused
            metrics["link"]["usbl_fixes_refused"] = nav.n_late_gated + nav.n_late_too_old
        surface = mission.link.surface_world_model
        if surface is not None and mission.perception is not None:
            sw = world_model_metrics(surface.world_model(), mission.perception.truth_targets)
            sw["world_model_json_objects"] = len(surface.world_model())
            sw["note"] = ("the world model on the surface vehicle, from the detections the acoustic link delivered "
                          "(surface_world_model.json); scored as world_model")
            metrics["surface_world_model"] = sw
    return metrics


def _outcome_suffix(metrics: dict[str, Any], runs_to_duration: bool = False) -> str:
    """Second title line: aborted, or not finished (not for a mission that runs to
    ``duration_s`` by design, such as target tracking)."""
    m = metrics["mission"]
    if m["aborted"]:
        return f"\nABORTED at {metrics['sim_time_s']:.0f} s: {m['abort_reason']}"
    if not m["finished"] and not runs_to_duration:
        return f"\nnot finished: stopped at duration_s ({metrics['sim_time_s']:.0f} s)"
    return ""


def map_layers(mission: Mission, tracking: Any, sim_time_s: float, overlay=None,
               extent: np.ndarray | None = None) -> dict[str, Any]:
    """The scene layers of ``map.png`` (keyword arguments of :func:`sim.outputs.map_plot.plot_map`):
    ``waypoints_ne`` (None for a buddy mission, which does not fly the survey plan),
    ``targets`` (fixed objects; movers are drawn as their true paths over ``sim_time_s`` with
    the tracker's estimate, :mod:`sim.outputs.tracking_overlay`, and bubble scatterers not at
    all), ``overlay`` (``overlay`` given, e.g. a scanning sonar's, then the movers') and
    ``extent_points_ne``.

    Args:
        mission: the finished mission; tracking: its :class:`TrackingEvaluation` or None.
    """
    scenario = mission.scenario
    movers = {m.name for m in scenario.world.movers}
    objects = [(o.name, o.centroid_ned, o.is_target) for o in mission.world.objects
               if o.name not in movers and o.class_name != BUBBLE_CLASS]
    draws, extents = [overlay] if overlay is not None else [], [extent] if extent is not None else []
    if movers:
        from sim.outputs.tracking_overlay import extent_points_ne, mover_paths_ned, tracking_overlay

        paths = mover_paths_ned(mission.physics.movers, sim_time_s)
        est = np.array(tracking.primary_est_ned, dtype=float).reshape(-1, 4)[:, 1:] if tracking is not None else None
        draws.append(tracking_overlay(paths, est, f"tracker estimate ({scenario.autonomy.tracking.mode})"))
        extents.append(extent_points_ne(paths, est))

    def draw_all(ax) -> None:
        for draw in draws:
            draw(ax)

    return {"waypoints_ne": None if scenario.autonomy.guidance.buddy.enabled else mission.waypoints_ne,
            "targets": objects, "overlay": draw_all if draws else None,
            "extent_points_ne": np.concatenate([np.asarray(e, dtype=float).reshape(-1, 2) for e in extents])
            if extents else None}


class _ProgressObserver:
    """Feeds the mission's step records to a :class:`MissionProgress`; a buddy mission (whose
    survey state machine stays ``idle``) shows its behaviour instead (``buddy follow``)."""

    sonar_frames = False  # ignores the sonar's renders (the pipelined loop need not ship them)
    sonar_truth = False  # nor their ground truth (the sonar need not compute it)

    def __init__(self, progress: MissionProgress, buddy: str | None = None) -> None:
        self.progress = progress
        self.buddy = buddy

    def on_start(self, info: Any) -> None:
        self.progress.start()

    def on_step(self, record: Any) -> None:
        self.progress.update(record.t_s, f"buddy {self.buddy}" if self.buddy else record.mode)

    def on_message(self, name: str, msg: Any) -> None:
        pass

    def on_end(self, summary: Any) -> None:
        self.progress.close(summary.sim_time_s)


def run_mission(
    scenario: Scenario, out: str | Path, *, nav_source: str = "estimate", rerun: bool = True,
    progress: bool = True, overwrite: bool = False, rosbag: bool | None = None, rosbag_fls_every: int | None = None,
    score_detections: bool = True, workers: int = 1,
) -> dict[str, Any]:
    """Run ``scenario`` and write metrics.json, trajectory.csv, world_model.json (objects in NED
    and latitude / longitude / depth), map.png (with an acoustic link, also
    surface_world_model.json and the link statistics under ``link`` in metrics.json)
    (with target tracking also tracking_error.png and tracking_boxplot.png, and the
    trackers' figures under ``tracking`` in metrics.json; and recording.rrd; with ``rosbag``, a
    ROS 2 bag folder ``rosbag/`` in MCAP storage, :class:`sim.ros2bag.recorder.RosbagRecorder`,
    every ``rosbag_fls_every``-th sonar frame; None takes the scenario's ``outputs.rosbag`` /
    ``outputs.rosbag_fls_every``) into ``out``. ``score_detections``: score the ATR against the
    frames' ground truth (:class:`sim.evaluation.detection_scoring.DetectionScorer`; its figures
    go under ``perception`` in metrics.json). ``workers`` > 1 pipelines the sonar and its
    perception in worker processes (:class:`sim.mission.Mission`; same outputs). Returns the metrics.

    Raises:
        OutputDirError: ``out`` is protected, a file, not creatable, or holds files that
            are not an earlier run (or an earlier run and ``overwrite`` is False). Raised
            before the mission starts; nothing is written then.
    """
    out_dir = check_output_dir(out, kind="run", overwrite=overwrite)
    staged = StagedOutput(out_dir, kind="run")
    with staged as partial:
        log = TrajectoryLog()
        observers: list[Any] = [log]
        scorer = DetectionScorer("", scenario.autonomy.atr.detector) if score_detections else None
        if scorer is not None:
            observers.append(scorer)  # before the recorder, which colours detections by it
        if rerun:
            from sim.outputs.rerun_recording import RerunRecorder

            observers.append(RerunRecorder(partial / "recording.rrd", scorer=scorer))
        if rosbag is None:
            rosbag = scenario.outputs.rosbag
        if rosbag_fls_every is None:
            rosbag_fls_every = scenario.outputs.rosbag_fls_every
        if rosbag:
            from sim.ros2bag.recorder import RosbagRecorder

            observers.append(RosbagRecorder(partial / "rosbag", fls_every=rosbag_fls_every))
        mission = Mission(scenario, nav_source=nav_source, observers=observers, workers=workers)
        if scorer is not None:
            if mission.perception is None:
                mission.observers.remove(scorer)
                scorer = None
            else:
                scorer.sonar_name = mission.fls.name
        msis = next(iter(p for p in mission.parts.processors.values() if hasattr(p, "localizer")), None)
        if msis is not None:
            from sim.msis_evaluation import LocalizationErrorObserver

            msis_obs = LocalizationErrorObserver(mission)
            mission.observers.append(msis_obs)
        buddy = scenario.autonomy.guidance.buddy
        mission.observers.append(_ProgressObserver(MissionProgress(scenario.name, planned_length_s(mission),
                                                                   enabled=progress),
                                                   buddy=buddy.behaviour if buddy.enabled else None))
        tracking = None
        if mission.parts.tracking is not None:
            from sim.evaluation.tracking_eval import evaluation_for

            tracking = evaluation_for(mission)
            mission.observers.append(tracking)
        mcm_obs = None
        if scenario.mcm.mode == "full":
            from sim.mcm.full_mode import McmFullObserver

            mcm_obs = McmFullObserver(scenario)
            mission.observers.append(mcm_obs)
        try:  # reset starts the pipeline's workers: a Ctrl-C from then on stops them too
            mission.reset()
            if workers > 1 and not mission.pipelined:
                print(f"{scenario.name}: --workers {workers}: this mission runs the serial loop (the pipeline takes "
                      "the FLS frames of a mission with perception and no tracker)", file=sys.stderr, flush=True)
            mission.run(progress=False)
        finally:
            mission.close()

        metrics = collect_metrics(mission, log, scorer)
        overlay = extent = None
        if msis is not None and msis_obs.err_fused_m:
            from sim.outputs.msis_overlay import basin_outline_ne, msis_overlay

            metrics["msis_localization"] = msis_obs.rms()
            overlay = msis_overlay(msis_obs, scenario.world.basin, msis.localizer)
            extent = basin_outline_ne(scenario.world.basin)
        mcm_result = mcm_obs.results(mission.seed) if mcm_obs is not None and mcm_obs.tiles else None
        if mcm_result is not None:
            from sim.mcm.figures import confirmed_objects_overlay

            overlay = confirmed_objects_overlay(mcm_result)
        log.write_csv(partial / "trajectory.csv")
        layers = map_layers(mission, tracking, metrics["sim_time_s"], overlay, extent)
        estimates, rejected = [], []
        origin = scenario.world.origin
        surface_targets = []
        if mission.perception is not None:
            write_json(partial / "world_model.json", with_geodetic(mission.perception.world_model_json(), origin))
            targets = mission.perception.target_objects()
            estimates = [(f"{o.id}", o.pos_ned, o.cov_ned) for o in targets]
            target_ids = {o.id for o in targets}
            rejected = [o.pos_ned for o in mission.perception.world_objects() if o.id not in target_ids]
        if mission.link is not None and mission.link.surface_world_model is not None:
            surface = mission.link.surface_world_model
            write_json(partial / "surface_world_model.json", with_geodetic(surface.to_json(), origin))
            surface_targets = [o.pos_ned for o in target_objects(surface.world_model())]
        plot_map(
            partial / "map.png",
            true_pos_ned=log.true_pos_ned, est_pos_ned=log.est_pos_ned, estimates=estimates, rejected_ned=rejected,
            title=(f"{scenario.name} seed {mission.seed} (nav: {nav_source})"
                   + _outcome_suffix(metrics, runs_to_duration=tracking is not None)),
            other_paths=list(log.other_paths_ned().items()), surface_estimates_ned=surface_targets,
            **layers,
        )
        if tracking is not None:
            metrics["tracking"] = tracking.metrics()
            tracking.plot(partial / "tracking_error.png", partial / "tracking_boxplot.png",
                          title=f"{scenario.name} seed {mission.seed}")
        if mcm_obs is not None and not mcm_obs.tiles:  # too short a run: its other outputs still count
            from sim.mcm.full_mode import no_tile_message

            metrics["mcm"] = {"tiles": 0, "note": no_tile_message(scenario)}
        elif mcm_result is not None:
            from sim.mcm.figures import summarise, write_figures

            write_json(partial / "mcm.json", mcm_result)
            write_figures(partial, [mcm_result], title=f"{scenario.name} seed {mission.seed}")
            metrics["mcm"] = {**summarise([mcm_result]), "detector": mcm_result["detector"]}
        write_json(partial / "metrics.json", metrics, decimals=METRICS_DECIMALS)
        staged.commit()
    return metrics
