"""Target tracking (and buddy guidance) as a mission feature ([P004]): the trackers take the
USBL fixes and the frames of their sonar; the buddy observer, when on, flies after the
tracked target instead of the survey.

Files: this module, :mod:`autonomy.tracking` (the onboard trackers),
:mod:`autonomy.guidance.buddy` (the buddy observer), :mod:`sim.evaluation.tracking_eval`
(scoring against the movers' truth), :mod:`sim.outputs.tracking_overlay` (the map).
Config: ``autonomy.tracking``, ``autonomy.guidance.buddy``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from autonomy.control.setpoint import Setpoint
from autonomy.guidance.buddy import BuddyObserver
from autonomy.messages import NavEstimate, UsblMsg
from sim.features.base import FeatureContext, LoopPorts, MissionFeature
from sim.features.base import fmt_or_na as _fmt
from sim.events.records import MissionObserver
from sim.dynamics.truth import VehicleTruth
from autonomy.tracking.onboard import TrackingStack


class TrackingFeature(MissionFeature):
    """The tracking stack on the USBL fixes and the sonar's frames, and the buddy observer.

    Attributes:
        stack: the :class:`autonomy.tracking.onboard.TrackingStack`.
        buddy: the buddy observer (None: the vehicle flies its survey).
        evaluation: the run's :class:`sim.evaluation.tracking_eval.TrackingEvaluation` (None
            outside a run's outputs).
    """

    name = "tracking"

    def __init__(self, ctx: FeatureContext) -> None:
        self.ctx = ctx
        auto = ctx.scenario.autonomy
        usbl, self.sonar = ctx.parts.sensors[auto.tracking.usbl_sensor], ctx.parts.sonar
        self.stack = TrackingStack(auto.tracking, auto.atr.classical, usbl_mount_body_m=usbl.mount.pos_body_m,
                                   usbl_mount_rpy_rad=usbl.mount.rpy_rad, sonar_mount_body_m=self.sonar.mount.pos_body_m,
                                   sonar_mount_rpy_rad=self.sonar.mount.rpy_rad)
        self.buddy: BuddyObserver | None = None
        if auto.guidance.buddy.enabled:
            vehicle = ctx.scenario.vehicle
            self.buddy = BuddyObserver(auto.guidance.buddy, float(np.deg2rad(vehicle.initial_rpy_deg[2])),
                                       float(vehicle.initial_pos_ned[2]))
        self.drives_guidance = self.buddy is not None
        self.evaluation: Any = None

    @classmethod
    def build(cls, ctx: FeatureContext) -> TrackingFeature | None:
        return cls(ctx) if ctx.scenario.autonomy.tracking.enabled else None

    @classmethod
    def runs_to_duration(cls, scenario) -> bool:
        return bool(scenario.autonomy.tracking.enabled)

    # -- the loop ------------------------------------------------------------------------
    def reset(self, ports: LoopPorts) -> None:
        self._ports = ports
        self.stack.reset()
        ports.on_message(UsblMsg, self.stack.on_usbl)
        ports.process_source(self.sonar.name, lambda render, _nav: self.stack.on_frame(render.frame))

    def start(self, truth: VehicleTruth, nav: NavEstimate) -> None:
        # the first vehicle pose (the prior: the start of the pose history, so that fixes
        # measured before the first autonomy period find a pose)
        for res in self.stack.on_nav(nav):
            self._ports.emit(self.sonar.name, res)

    def after_nav(self, t_s: float, nav: NavEstimate) -> None:
        timer = self._ports.timer
        with timer.stage("tracking"):
            results = self.stack.on_nav(nav)  # frames that waited for this pose
        with timer.stage("observers"):
            for res in results:
                self._ports.emit(self.sonar.name, res)

    def setpoint(self, t_s: float, nav: NavEstimate) -> Setpoint | None:
        est = self.stack.primary.estimate(t_s)
        return self.buddy.update(nav, None if est is None else est[0][:3])

    # -- a run's outputs -------------------------------------------------------------------
    def observers(self, options: Mapping[str, Any]) -> list[MissionObserver]:
        from sim.evaluation.tracking_eval import evaluation_for

        self.evaluation = evaluation_for(self.stack, self.ctx.physics.movers, self.sonar)
        return [self.evaluation]

    def progress_label(self) -> str | None:
        return f"buddy {self.ctx.scenario.autonomy.guidance.buddy.behaviour}" if self.buddy is not None else None

    def planned_length_s(self) -> float | None:
        # a buddy mission flies no survey plan: it runs to duration_s
        return float(self.ctx.scenario.duration_s) if self.buddy is not None else None

    def add_metrics(self, metrics: dict[str, Any], log: Any) -> None:
        if self.evaluation is not None:
            metrics["tracking"] = self.evaluation.metrics()

    def map_layers(self, layers: dict[str, Any]) -> None:
        if self.buddy is not None:  # it does not fly the survey plan
            layers["waypoints_ne"] = None
        if self.evaluation is not None:
            layers["tracker_estimate_ned"] = (
                np.array(self.evaluation.primary_est_ned, dtype=float).reshape(-1, 4)[:, 1:],
                f"tracker estimate ({self.ctx.scenario.autonomy.tracking.mode})")

    def write_outputs(self, out_dir: Path, metrics: dict[str, Any], title: str) -> None:
        if self.evaluation is not None:
            self.evaluation.plot(out_dir / "tracking_error.png", out_dir / "tracking_boxplot.png", title=title)

    @classmethod
    def summary_lines(cls, metrics: Mapping[str, Any]) -> list[str]:
        if "tracking" not in metrics:
            return []
        tr = metrics["tracking"]
        if not any(v.get("n") for v in tr["errors"].values()):
            return [f"tracking ({tr['mode']}): nothing scored (errors count from {tr.get('scored_from_s', 0):g} s "
                    "into the run, once the filters have started); raise duration_s"]
        errs = ", ".join(f"{k} {_fmt(v.get('mean_m'), '.2f')} +- {_fmt(v.get('std_m'), '.2f')} m"
                         for k, v in tr["errors"].items())
        lines = [f"tracking ({tr['mode']}; 3-D error, horizontal in metrics.json): {errs}; sonar used in "
                 f"{_fmt(100 * tr['fused_sonar_step_fraction'], '.0f')} % "
                 f"of steps; target in view {_fmt(100 * tr['target_in_fov_fraction'], '.0f')} %"]
        if "nees_horizontal" in tr:
            nees = tr["nees_horizontal"]
            lines.append("tracking consistency, mean horizontal NEES (2 if the filter's covariance is right, more: "
                         "overconfident): " + ", ".join(f"{k} {_fmt(v.get('mean'), '.2f')}" for k, v in nees.items()))
        return lines
