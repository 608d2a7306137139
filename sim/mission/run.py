"""Fly a mission and write its results into a run folder.

Results are written into a hidden ``.<name>.partial`` folder next to the output folder and
moved into place only when complete (:class:`sim.outputs.run_dir.StagedOutput`), so a
failed or interrupted run never leaves half-written results that look finished, and an
earlier run being replaced is removed only once the new one is in place.
"""

from __future__ import annotations

import sys
from pathlib import Path
from collections.abc import Sequence
from typing import Any

import numpy as np

from scenarios.schema import Scenario
from sim.evaluation.detection_scoring import DetectionScorer
from sim.events.records import ObserverBase
from sim.features import runs_to_duration
from sim.features.base import MissionFeature
from sim.mission.loop import Mission
from sim.outputs.json_files import write_json
from sim.outputs.map_plot import plot_map
from sim.outputs.progress import MissionProgress
from sim.outputs.run_dir import StagedOutput, check_output_dir
from sim.outputs.trajectory_log import TrajectoryLog
from sim.scene.movers import BUBBLE_CLASS
from sim.outputs.tracking_overlay import extent_points_ne, mover_paths_ned, tracking_overlay
from scenarios.load import scenario_yaml
from sim.outputs.rerun_recording import RerunRecorder
from sim.ros2bag.recorder import RosbagRecorder
from sim.outputs.ping360_log import Ping360LogRecorder
from sim.outputs.xtf_log import XtfRecorder

METRICS_DECIMALS = 4


def planned_length_s(mission: Mission) -> float:
    """Planned mission length, s: start delay plus the survey path at the survey speed.

    Used as the 100 % of the progress display; capped by the scenario's duration (a feature
    may decide it instead: a buddy mission, which flies no survey, runs to the duration).
    """
    scn = mission.scenario
    for feature in mission.features:
        planned = feature.planned_length_s()
        if planned is not None:
            return planned
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


def collect_metrics(mission: Mission, log: TrajectoryLog) -> dict[str, Any]:
    """The figures of a finished mission: the core ones (navigation, the sonars' frames), then
    each feature's (:meth:`sim.features.base.MissionFeature.add_metrics`: detections as the
    scorer counted them, the world model, the link, tracking, ...), in feature order."""
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
    for feature in mission.features:
        feature.add_metrics(metrics, log)
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


def map_layers(mission: Mission, sim_time_s: float) -> dict[str, Any]:
    """The scene layers of ``map.png`` (keyword arguments of :func:`sim.outputs.map_plot.plot_map`):
    ``waypoints_ne``, ``targets`` (fixed objects; movers are drawn as their true paths over
    ``sim_time_s``, :mod:`sim.outputs.tracking_overlay`, with a tracker's estimate where a
    feature gives one, and bubble scatterers not at all), ``overlay`` (the features' overlays,
    then the movers') and ``extent_points_ne``; each feature adds its layers
    (:meth:`sim.features.base.MissionFeature.map_layers`)."""
    scenario = mission.scenario
    movers = {m.name for m in scenario.world.movers}
    objects = [(o.name, o.centroid_ned, o.is_target) for o in mission.world.objects
               if o.name not in movers and o.class_name != BUBBLE_CLASS]
    layers: dict[str, Any] = {"waypoints_ne": mission.waypoints_ne, "targets": objects, "overlays": [], "extents": []}
    for feature in mission.features:
        feature.map_layers(layers)
    draws, extents = layers.pop("overlays"), layers.pop("extents")
    tracker = layers.pop("tracker_estimate_ned", None)
    if movers:
        paths = mover_paths_ned(mission.physics.movers, sim_time_s)
        est, label = tracker if tracker is not None else (None, "tracker estimate")
        draws.append(tracking_overlay(paths, est, label))
        extents.append(extent_points_ne(paths, est))

    def draw_all(ax) -> None:
        for draw in draws:
            draw(ax)

    layers["overlay"] = draw_all if draws else None
    layers["extent_points_ne"] = (np.concatenate([np.asarray(e, dtype=float).reshape(-1, 2) for e in extents])
                                  if extents else None)
    return layers


class _ProgressObserver(ObserverBase):
    """Feeds the mission's step records to a :class:`MissionProgress`; a buddy mission (whose
    survey state machine stays ``idle``) shows its behaviour instead (``buddy follow``)."""

    sonar_frames = False  # ignores the sonar's renders (the pipelined loop need not ship them)
    sonar_truth = False  # nor their ground truth (the sonar need not compute it)

    def __init__(self, progress: MissionProgress, label: str | None = None) -> None:
        self.progress = progress
        self.label = label

    def on_start(self, info: Any) -> None:
        self.progress.start()

    def on_step(self, record: Any) -> None:
        self.progress.update(record.t_s, self.label or record.mode)

    def on_message(self, name: str, msg: Any) -> None:
        pass

    def on_end(self, summary: Any) -> None:
        self.progress.close(summary.sim_time_s)


def run_mission(
    scenario: Scenario, out: str | Path, *, nav_source: str = "estimate", rerun: bool = True,
    progress: bool = True, overwrite: bool = False, rosbag: bool | None = None, rosbag_fls_every: int | None = None,
    score_detections: bool = True, workers: int = 1, features: Sequence[type[MissionFeature]] = (),
    ping360_log: bool | None = None, xtf: bool | None = None,
) -> dict[str, Any]:
    """Run ``scenario`` and write metrics.json, scenario.yaml (the scenario as flown, fully
    resolved: ``auvsim run OUT/scenario.yaml`` flies it again), trajectory.csv, world_model.json (objects in NED
    and latitude / longitude / depth), map.png (with an acoustic link, also
    surface_world_model.json and the link statistics under ``link`` in metrics.json)
    (with target tracking also tracking_error.png and tracking_boxplot.png, and the
    trackers' figures under ``tracking`` in metrics.json; and recording.rrd; with ``rosbag``, a
    ROS 2 bag folder ``rosbag/`` in MCAP storage, :class:`sim.ros2bag.recorder.RosbagRecorder`,
    every ``rosbag_fls_every``-th sonar frame; None takes the scenario's ``outputs.rosbag`` /
    ``outputs.rosbag_fls_every``; with ``ping360_log``, the scanning sonar's pings as Blue
    Robotics ping-protocol messages in ``ping360/``, :mod:`sim.outputs.ping360_log`; None: the
    scenario's ``outputs.ping360_log``; with ``xtf``, the side-scan pings as eXtended Triton Format
    files in ``xtf/``, :mod:`sim.outputs.xtf_log`; None: the scenario's ``outputs.xtf``) into ``out``. ``score_detections``: score the ATR against the
    frames' ground truth (:class:`sim.evaluation.detection_scoring.DetectionScorer`; its figures
    go under ``perception`` in metrics.json). ``workers`` > 1 pipelines the sonar and its
    perception in worker processes (:class:`sim.mission.Mission`; same outputs). ``features``:
    feature classes of the caller's own (:class:`sim.features.base.MissionFeature`), built after
    the shipped ones: their observers, metrics, map layers, files and ``runs_to_duration`` count
    as the shipped ones' do (print their summary lines with :func:`sim.features.summary_lines`).
    Returns the metrics.

    Raises:
        OutputDirError: ``out`` is protected, a file, not creatable, or holds files that
            are not an earlier run (or an earlier run and ``overwrite`` is False). Raised
            before the mission starts; nothing is written then.
    """
    out_dir = check_output_dir(out, kind="run", overwrite=overwrite)
    staged = StagedOutput(out_dir, kind="run")
    with staged as partial:
        log = TrajectoryLog()
        mission = Mission(scenario, nav_source=nav_source, observers=[log], workers=workers, features=features)
        evaluations = [obs for feature in mission.features
                       for obs in feature.observers({"score_detections": score_detections})]
        mission.observers.extend(evaluations)  # before the recorders, which colour detections by the scorer
        scorer = next((o for o in evaluations if isinstance(o, DetectionScorer)), None)
        if rerun:
            mission.observers.append(RerunRecorder(partial / "recording.rrd", scorer=scorer))
        if rosbag is None:
            rosbag = scenario.outputs.rosbag
        if rosbag_fls_every is None:
            rosbag_fls_every = scenario.outputs.rosbag_fls_every
        if rosbag:
            mission.observers.append(RosbagRecorder(partial / "rosbag", fls_every=rosbag_fls_every))
        if ping360_log is None:
            ping360_log = scenario.outputs.ping360_log
        if ping360_log:
            mission.observers.append(Ping360LogRecorder(partial / "ping360"))
        if xtf is None:
            xtf = scenario.outputs.xtf
        if xtf:
            mission.observers.append(XtfRecorder(partial / "xtf"))
        label = next((f.progress_label() for f in mission.features if f.progress_label() is not None), None)
        mission.observers.append(_ProgressObserver(MissionProgress(scenario.name, planned_length_s(mission),
                                                                   enabled=progress), label=label))
        try:  # reset starts the pipeline's workers: a Ctrl-C from then on stops them too
            mission.reset()
            if workers > 1 and not mission.pipelined:
                print(f"{scenario.name}: --workers {workers}: this mission runs the serial loop (the pipeline takes "
                      "the FLS frames of a mission with perception and no tracker)", file=sys.stderr, flush=True)
            mission.run(progress=False)
        finally:
            mission.close()

        metrics = collect_metrics(mission, log)
        log.write_csv(partial / "trajectory.csv")
        layers = map_layers(mission, metrics["sim_time_s"])
        title = f"{scenario.name} seed {mission.seed}"
        for feature in mission.features:
            feature.write_outputs(partial, metrics, title)
        plot_map(
            partial / "map.png",
            true_pos_ned=log.true_pos_ned, est_pos_ned=log.est_pos_ned,
            title=(f"{title} (nav: {nav_source})"
                   + _outcome_suffix(metrics, runs_to_duration=runs_to_duration(scenario, features))),
            other_paths=list(log.other_paths_ned().items()),
            **layers,
        )
        write_json(partial / "metrics.json", metrics, decimals=METRICS_DECIMALS)

        (partial / "scenario.yaml").write_text(scenario_yaml(scenario))  # `auvsim run OUT/scenario.yaml` reruns it
        staged.commit()
    return metrics
