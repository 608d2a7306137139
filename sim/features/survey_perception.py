"""Survey perception as a mission feature: ATR -> geolocalisation -> world model on the frames
of the processed forward-looking sonar, pipelined in worker processes when the loop may use them.

Files: this module (the loop's side and a run's outputs), :mod:`sim.features.perception` (the onboard
chain), :mod:`sim.process.sonar_pipeline` (the workers), :mod:`sim.evaluation.detection_scoring`
(the scoring observer). Config: ``autonomy.atr``, ``autonomy.localization``,
``autonomy.world_model``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from sim.features.base import FeatureContext, LoopPorts, MissionFeature
from sim.outputs.json_files import with_geodetic, write_json
from sim.features.base import fmt_or_na as _fmt
from sim.features.perception import Perception
from sim.events.records import MissionObserver, PerceptionResult
from sim.process.sonar_pipeline import FrameTicket, SonarPipeline
from sim.dynamics.truth import VehicleTruth
from sim.evaluation.detection_scoring import DetectionScorer


class SurveyPerceptionFeature(MissionFeature):
    """ATR, geolocalisation and the world model on the processed sonar's frames.

    Built when the mission has a processed forward-looking sonar, perception is asked for
    and no tracker reads that sonar. With ``workers`` > 1 and a sonar of fixed latency the
    frames and their detection run in worker processes (:class:`sim.process.sonar_pipeline.SonarPipeline`),
    with the serial loop's results bit for bit.

    Attributes:
        perception: the :class:`sim.features.perception.Perception` chain.
        sonar: the sensor whose frames it reads.
        scorer: the detection scorer of a run (None: not scored, or no run outputs).
    """

    name = "survey_perception"

    def __init__(self, ctx: FeatureContext) -> None:
        self.ctx = ctx
        self.sonar = ctx.parts.sonar
        self.perception = Perception(ctx.scenario, self.sonar, ctx.physics.world.seabed, ctx.parts.region_waypoints_ne,
                                     nav_source=ctx.nav_source)
        self.pipeline: SonarPipeline | None = None
        self.scorer: Any = None
        self._ports: LoopPorts | None = None

    @classmethod
    def build(cls, ctx: FeatureContext) -> SurveyPerceptionFeature | None:
        if ctx.parts.sonar is None or not ctx.perception or ctx.scenario.autonomy.tracking.enabled:
            return None
        return cls(ctx)

    # -- the loop ------------------------------------------------------------------------
    def reset(self, ports: LoopPorts) -> None:
        self.close()
        self._ports = ports
        self.perception.reset()
        sonar = self.sonar
        if self.ctx.workers > 1 and sonar.fixed_latency:
            # the scheduler gets a ticket, not the frame, to time the delivery by
            self.pipeline = SonarPipeline(self.ctx.physics, sonar, self.perception,
                                          frames=any(o.sonar_frames for o in ports.observers))
            self.captures = frozenset({sonar.name})
            ports.consume(FrameTicket, self._deliver_ticket)
        else:
            self.captures = frozenset()
            ports.process_source(sonar.name, self.perception.process)

    def capture(self, name: str, truth: VehicleTruth) -> FrameTicket:
        return self.pipeline.capture(truth)  # rendered on a worker from a copy of the scene now

    def _deliver_ticket(self, name: str, ticket: FrameTicket) -> None:
        # perception with the estimate of now (moved to the capture time)
        self.pipeline.deliver(name, ticket, self._ports.nav_filter.estimate())

    def before_nav(self, t_s: float, truth: VehicleTruth) -> None:
        pipeline = self.pipeline
        if pipeline is not None and pipeline.busy and self._ports.has_result_handler(PerceptionResult):
            # a handler (the acoustic link) takes results at the time they are made: take this
            # step's frames now, as the serial loop does (rendering still overlaps; same results)
            with self._ports.timer.stage("pipeline_wait"):
                self._ports.to_observers(pipeline.ready(wait=True))

    def end_of_step(self) -> None:
        if self.pipeline is not None and self.pipeline.busy:
            with self._ports.timer.stage("perception"):  # this process's part: geolocalisation, world model
                ready = list(self.pipeline.ready())
            self._ports.to_observers(ready)

    def flush(self) -> None:
        if self.pipeline is not None and self.pipeline.busy:
            with self._ports.timer.stage("pipeline_wait"):
                self._ports.to_observers(self.pipeline.ready(wait=True))

    def close(self) -> None:
        if self.pipeline is not None:
            self.pipeline.close()
            self.pipeline = None

    def worker_pids(self) -> list[int]:
        return list(self.pipeline.pids) if self.pipeline is not None else []

    def results(self) -> Perception:
        """The perception chain with every frame delivered so far processed."""
        self.flush()
        if self.pipeline is not None:
            self.pipeline.sync()
        return self.perception

    # -- a run's outputs -------------------------------------------------------------------
    def observers(self, options: Mapping[str, Any]) -> list[MissionObserver]:
        if not options.get("score_detections", True):
            return []

        self.scorer = DetectionScorer(self.sonar.name, self.ctx.scenario.autonomy.atr.detector)
        return [self.scorer]

    def add_metrics(self, metrics: dict[str, Any], log: Any) -> None:
        perception = self.results()
        if self.scorer is not None:
            metrics["perception"].update(self.scorer.metrics())
        wm = perception.world_model_metrics()
        n_all = len(perception.world_objects())
        n_targets = n_all - int(wm.get("objects_not_target", 0))
        wm["world_model_json_objects"] = n_all
        wm["note"] = (f"world_model.json holds all {n_all} objects the world model keeps; {n_targets} it classifies "
                      f"as targets are scored against the true targets (objects, matched, missed, false); "
                      f"{n_all - n_targets} it classifies as not targets (rocks, clutter) are listed there "
                      "but not scored")
        metrics["world_model"] = wm

    def map_layers(self, layers: dict[str, Any]) -> None:
        perception = self.results()
        targets = perception.target_objects()
        layers["estimates"] = [(f"{o.id}", o.pos_ned, o.cov_ned) for o in targets]
        target_ids = {o.id for o in targets}
        layers["rejected_ned"] = [o.pos_ned for o in perception.world_objects() if o.id not in target_ids]

    def write_outputs(self, out_dir: Path, metrics: dict[str, Any], title: str) -> None:
        write_json(out_dir / "world_model.json",
                   with_geodetic(self.results().world_model_json(), self.ctx.scenario.world.origin))

    @classmethod
    def summary_lines(cls, metrics: Mapping[str, Any]) -> list[str]:
        lines = []
        if "note" in metrics.get("perception", {}):  # several sonars: say which one perception read
            per = metrics["perception"]
            counts = ", ".join(f"{k} {v}" for k, v in per["fls_frames_by_sensor"].items())
            lines.append(f"sonar frames: {counts}; {per['note']}")
        if "world_model" in metrics:
            wm = metrics["world_model"]
            n_other = wm.get('objects_not_target', 0)
            lines.append(
                f"world model: {wm['objects']} targets ({n_other} more object{'' if n_other == 1 else 's'} classified "
                f"not target), {wm['matched']} matched, {wm['missed']} missed, {wm['false']} false, "
                f"mean error {_fmt(wm.get('mean_position_error_m'), '.2f', ' m')}, GOSPA {_fmt(wm.get('gospa'), '.2f')}")
            nees = wm.get("nees_horizontal")
            if nees and nees["n"]:
                lo, hi = nees["band_95"]
                verdict = ("inside it" if lo <= nees["mean"] <= hi else
                           "below it: ellipses larger than the errors" if nees["mean"] < lo else
                           "above it: ellipses smaller than the errors")
                lines.append(
                    f"world model ellipses: mean horizontal NEES {nees['mean']:.2f} over {nees['n']} matched targets "
                    f"(a consistent map: 2, 95 % band {lo:.2f}-{hi:.2f}, {verdict}; one run's targets share its "
                    "navigation error, so judge over seeds)")
        return lines


__all__ = ["SurveyPerceptionFeature"]
