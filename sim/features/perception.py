"""The mission's perception stage: ATR on each FLS frame -> geolocalisation -> PMHA.

Runs the onboard code (``autonomy.atr``, ``autonomy.localization``,
``autonomy.world_model``). It never reads the frame's ground truth (except with
``nav_source='truth'``, which replaces the navigation estimate by the true pose, as paper
000's simulated evaluation); scoring detections against the truth is the job of an observer
(:class:`sim.evaluation.detection_scoring.DetectionScorer`), outside the loop.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from autonomy.frames import euler_from_rot
from autonomy.localization import fls_visibility, localize
from autonomy.messages import Detection, NavEstimate
from autonomy.navigation.pose_at import estimate_at
from autonomy.world_model import CLASS_NAMES, PMHA
from autonomy.world_model.surface import SonarFootprint
from scenarios.schema import Scenario
from sim.evaluation.world_model_score import score_world_model
from sim.events.records import PerceptionResult
from sim.features.shared_detector import shared_detector
from sim.scene.seabed import Seabed
from sim.sensors.fls import FlsRender, FlsSensor

TARGET_CLASS = CLASS_NAMES[0]  # the world model's class of objects of potential interest


class Perception:
    """ATR + geolocalisation + PMHA for one mission.

    Args:
        scenario: the scenario (uses ``autonomy.atr``, ``.localization``, ``.world_model``).
        fls: the sonar whose frames arrive (for mount extrinsics and field of view).
        seabed: the true seabed (only for ``nav_source='truth'`` altitudes and the region depth).
        waypoints_ne: (k, 2) the survey plan, which bounds the surveyed region.
        nav_source: ``estimate`` or ``truth``.
    """

    def __init__(self, scenario: Scenario, fls: FlsSensor, seabed: Seabed, waypoints_ne: np.ndarray, *,
                 nav_source: str = "estimate") -> None:
        self.scenario = scenario
        self.fls = fls
        self.seabed = seabed
        self.nav_source = nav_source
        auto = scenario.autonomy
        self.detector = shared_detector(auto.atr)  # one per configuration and process
        #: The ATR's class labels (the class table of the detection messages).
        self.class_names: tuple[str, ...] = tuple(self.detector.class_names)
        self.loc_cfg = auto.localization
        self.wm_cfg = auto.world_model
        self.truth_targets = np.array([t.pos_ned for t in scenario.world.targets if t.is_target], dtype=float)
        self.region_ned = self._survey_region(np.asarray(waypoints_ne, dtype=float).reshape(-1, 2))
        self.reset()

    def _survey_region(self, waypoints_ne: np.ndarray) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """Surveyed volume: the survey waypoints' bounding box grown by ``region_margin_m``,
        from the surface to below the deepest seabed point in it."""
        margin = self.wm_cfg.region_margin_m
        lo = np.min(waypoints_ne, axis=0) - margin
        hi = np.max(waypoints_ne, axis=0) + margin
        depth = float(np.max(self.seabed.depth_at(*np.meshgrid(np.linspace(lo[0], hi[0], 9),
                                                                np.linspace(lo[1], hi[1], 9))))) + 1.0
        return (float(lo[0]), float(lo[1]), 0.0), (float(hi[0]), float(hi[1]), depth)

    def reset(self) -> None:
        self.pmha = PMHA(self.wm_cfg, region_ned=self.region_ned)
        self.n_frames = 0

    # -- per frame ----------------------------------------------------------------------
    def _truth_nav(self, render: FlsRender) -> NavEstimate:
        """Navigation message holding the true pose at capture (zero covariance)."""
        tr = render.truth
        R_nb = tr.R_ns @ self.fls.R_bs.T
        pos_body = tr.pos_ned - R_nb @ self.fls.mount_pos_body_m
        altitude = float(self.seabed.depth_at(pos_body[0], pos_body[1])) - float(pos_body[2])
        return NavEstimate(t_s=tr.t_s, pos_ned=pos_body, rpy_rad=euler_from_rot(R_nb), vel_body_mps=np.zeros(3),
                           rate_body_radps=np.zeros(3), cov_pos_ned=np.zeros((3, 3)), cov_yaw_rad2=0.0,
                           altitude_m=altitude)

    def process(self, render: FlsRender, nav: NavEstimate,
                detections: list[Detection] | None = None) -> PerceptionResult:
        """Run perception on one delivered frame; returns the detections, their
        geolocalisation and the updated world model.

        ``detections``: this frame's ATR detections when already made (the pipelined loop
        runs the detector, which reads only the frame, in a worker process; then ``render``
        need not carry the images); None: run :attr:`detector` on ``render.frame``."""
        frame = render.frame
        self.n_frames += 1
        if detections is None:
            detections = self.detector.detect(frame)

        # the pose at the frame's capture: the true one, or the estimate (of its delivery,
        # latency and a tick later) moved back to the capture time
        nav_loc = self._truth_nav(render) if self.nav_source == "truth" else estimate_at(nav, frame.t_s)
        localized = [localize(d, nav_loc, self.fls.mount_pos_body_m, self.fls.mount_roll_tilt_yaw_rad, self.loc_cfg,
                              geometry=frame.geometry) for d in detections]
        g = self.fls.geometry
        visible = fls_visibility(nav_loc.pos_ned, nav_loc.rpy_rad, self.fls.mount_pos_body_m, self.fls.mount_roll_tilt_yaw_rad,
                                 range_min_m=g.window_near_m, range_max_m=g.window_far_m, fov_rad=g.fov_rad,
                                 vertical_fov_rad=g.vertical_beamwidth_rad, margin_m=1.0)
        self.pmha.update(frame.t_s, localized, visible)
        return PerceptionResult(t_s=frame.t_s, detections=tuple(detections), localized=tuple(localized),
                                world_objects=tuple(self.pmha.world_model()))

    def sonar_footprint(self) -> SonarFootprint:
        """The sonar's mount and field of view, as the surface world model places it."""
        g = self.fls.geometry
        return SonarFootprint(tuple(float(v) for v in self.fls.mount_pos_body_m),
                              tuple(float(v) for v in self.fls.mount_roll_tilt_yaw_rad), g.window_near_m, g.window_far_m,
                              g.fov_rad, g.vertical_beamwidth_rad)

    # -- results --------------------------------------------------------------------------
    def world_objects(self) -> list[Any]:
        return self.pmha.world_model()

    def world_model_json(self) -> dict:
        return self.pmha.to_json()

    def target_objects(self) -> list[Any]:
        """World objects the world model classifies as targets (most probable class)."""
        return target_objects(self.world_objects())

    def world_model_metrics(self) -> dict[str, Any]:
        """The onboard world model scored against the true targets (:func:`world_model_metrics`)."""
        return world_model_metrics(self.world_objects(), self.truth_targets)


def target_objects(objects: list[Any]) -> list[Any]:
    """The world objects classified as targets (most probable class)."""
    return [o for o in objects if o.class_name == TARGET_CLASS]


def world_model_metrics(objects: list[Any], truth_targets: np.ndarray) -> dict[str, Any]:
    """Targets of a world model (its :class:`autonomy.world_model.WorldObject` list) scored
    against the true targets ((k, 3) NED m): optimal assignment within 2 m, GOSPA c = 2 m,
    p = 1, alpha = 2. Objects the world model itself classifies as not-targets are counted
    apart, not as false targets.

    ``nees_horizontal``: the matched targets' horizontal (north, east) NEES against the true
    positions with the world model's covariance (each pair's ``nees`` too), their mean and
    its chi-square 95 % band (:func:`sim.evaluation.nees.nees_summary`): a mean within the
    band means the map's ellipses say how far off its positions are."""
    from sim.evaluation.nees import horizontal_nees, nees_summary

    targets = target_objects(objects)
    est = np.array([o.pos_ned for o in targets], dtype=float).reshape(-1, 3)
    truth = np.asarray(truth_targets, dtype=float).reshape(-1, 3)
    s = score_world_model(est, truth, match_radius_m=2.0, gospa_c_m=2.0, gospa_p=1.0)
    out = {k: v for k, v in s.items() if k in ("objects", "matched", "missed", "false", "mean_position_error_m",
                                                 "gospa", "pairs")}
    out["objects_not_target"] = len(objects) - len(targets)
    nees = []
    for pair in out["pairs"]:
        o = targets[pair["estimate"]]
        pair["estimate_id"] = o.id
        pair["nees"] = horizontal_nees(np.asarray(o.pos_ned[:2]) - truth[pair["truth"], :2],
                                       np.asarray(o.cov_ned)[:2, :2])
        nees.append(pair["nees"])
    out["nees_horizontal"] = nees_summary(nees, dof=2)
    return out
