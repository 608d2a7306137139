"""Active inspection as a mission feature: the world model's updates reach the inspection
guidance, and a run reports what the inspection did.

Files: this module (the loop's side and a run's outputs), :mod:`autonomy.guidance.inspection`
(the onboard guidance), :mod:`autonomy.guidance.inspection_planner` (the planner).
Config: ``autonomy.guidance.inspection``.

The guidance is the survey state machine's (built by :func:`sim.mission.parts.build_mission_parts`),
so the dive, the surfacing and the aborts are the lawnmower's. This feature hands it each
perception result's world objects as they are made (a result handler: the pipelined loop then
delivers them at the serial loop's times), emits the planner's goal to the observers when it
changes (``inspection`` messages: :class:`sim.events.records.InspectionGoal`), and scores the legs against the
scene's true objects: a leg aimed at an object that ends up false (not in the final world
model, or more than ``FALSE_RADIUS_M`` from every true object, target or not) is a reactive
motion the world model should not have caused.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from autonomy.guidance.inspection import InspectionGuidance
from autonomy.guidance.inspection_planner import semi_major_2sigma_m
from sim.events.records import InspectionGoal, PerceptionResult
from sim.features.base import FeatureContext, LoopPorts, MissionFeature
from sim.features.base import fmt_or_na as _fmt
from sim.features.survey_perception import SurveyPerceptionFeature

#: An aimed-at object farther than this from every true object is a false one, m (the world
#: model's match radius).
FALSE_RADIUS_M = 2.0


class InspectionFeature(MissionFeature):
    """World-model updates to the inspection guidance; the inspection's metrics and map layers.

    Attributes:
        guidance: the mission's :class:`autonomy.guidance.inspection.InspectionGuidance`.
        legs: one dict per leg the vehicle was sent on (object, times, outcome, ellipses).
    """

    name = "inspection"

    def __init__(self, ctx: FeatureContext) -> None:
        self.ctx = ctx
        self.guidance: InspectionGuidance = ctx.parts.guidance
        self.has_perception = SurveyPerceptionFeature in ctx.features
        self._ports: LoopPorts | None = None

    @classmethod
    def build(cls, ctx: FeatureContext) -> InspectionFeature | None:
        if not ctx.scenario.autonomy.guidance.inspection.enabled:
            return None
        return cls(ctx)

    def planned_length_s(self) -> float | None:
        # the coverage pass is only the start: the mission may inspect until its time budget
        scn = self.ctx.scenario
        return float(min(scn.autonomy.guidance.inspection.time_budget_s, scn.duration_s))

    # -- the loop ------------------------------------------------------------------------
    def reset(self, ports: LoopPorts) -> None:
        self._ports = ports
        ports.on_result(PerceptionResult, self._on_result)
        self.legs: list[dict[str, Any]] = []
        self._leg = None
        self._last_goal: tuple | None = None
        self._phase_path: list[tuple[str, float, float]] = []
        self._t_s = 0.0

    def _on_result(self, name: str, result: PerceptionResult) -> None:
        with self._ports.timer.stage("inspection_planner"):
            self.guidance.on_world_model(result.t_s, result.world_objects)

    def end_of_step(self) -> None:
        g = self.guidance
        t_s = self._ports.t_s
        if g.leg is not self._leg:
            if self._leg is not None and self.legs and self.legs[-1]["t_end_s"] is None:
                self._close_leg(t_s)
            if g.leg is not None:
                obj = self.guidance.object_by_id(g.leg.object_id)
                self.legs.append(dict(
                    object_id=g.leg.object_id, heading_deg=round(math.degrees(g.leg.heading_rad), 1),
                    start_ne_m=[round(v, 3) for v in g.leg.start_ne_m], end_ne_m=[round(v, 3) for v in g.leg.end_ne_m],
                    t_assigned_s=round(t_s, 2), t_end_s=None, outcome=None,
                    wm_2sigma_before_m=None if obj is None else round(semi_major_2sigma_m(obj.cov_ned[:2, :2]), 4),
                    look_2sigma_before_m=round(g.leg.now_2sigma_m, 4),
                    look_2sigma_predicted_m=round(g.leg.predicted_2sigma_m, 4),
                    cov_before_ned=None if obj is None else np.asarray(obj.cov_ned)[:2, :2].tolist(),
                    pos_before_ned=None if obj is None else np.asarray(obj.pos_ned).tolist()))
            self._leg = g.leg
        if g.phase != "done":  # the path by phase, a point a second (and at each change), for the map
            p = g.pos_ne_m
            if not self._phase_path or self._phase_path[-1][0] != g.phase or t_s - self._t_s >= 1.0:
                self._phase_path.append((g.phase, float(p[0]), float(p[1])))
                self._t_s = t_s
        goal = g.goal
        key = None if goal is None else (goal["phase"], goal.get("object_id"), tuple(goal["tour"]))
        if key != self._last_goal:
            self._last_goal = key
            self._ports.emit(self.name, InspectionGoal(
                t_s, "done" if goal is None else goal["phase"], None if goal is None else goal.get("object_id"),
                None if goal is None else goal.get("start_ne_m"), None if goal is None else goal.get("end_ne_m"),
                () if goal is None else tuple(goal["tour"])))

    def _close_leg(self, t_s: float) -> None:
        leg = self.legs[-1]
        leg["t_end_s"] = round(t_s, 2)
        ends = [e for e in self.guidance.events if e.object_id == leg["object_id"] and e.event in ("leg_end", "leg_dropped")
                and e.t_s >= leg["t_assigned_s"] - 1e-9]
        started = any(e.event == "leg_start" and e.object_id == leg["object_id"] and e.t_s >= leg["t_assigned_s"] - 1e-9
                      for e in self.guidance.events)
        leg["started"] = started
        leg["outcome"] = "completed" if ends and ends[-1].event == "leg_end" else (
            f"ended early: {ends[-1].detail}" if ends else "stopped: mission ended")
        obj = self.guidance.object_by_id(leg["object_id"])
        leg["wm_2sigma_after_m"] = None if obj is None else round(semi_major_2sigma_m(obj.cov_ned[:2, :2]), 4)
        leg["look_2sigma_after_m"] = None if obj is None else round(self.guidance.planner.look_2sigma_m(obj), 4)

    def finish(self, t_s: float) -> None:
        if self.legs and self.legs[-1]["t_end_s"] is None:
            self._close_leg(t_s)

    # -- a run's outputs -------------------------------------------------------------------
    def _final_objects(self) -> list:
        feature = self.ctx.features.get(SurveyPerceptionFeature)
        return feature.results().world_objects() if feature is not None else list(self.guidance.objects)

    def add_metrics(self, metrics: dict[str, Any], log: Any) -> None:
        g, cfg = self.guidance, self.ctx.scenario.autonomy.guidance.inspection
        final = {o.id: o for o in self._final_objects()}
        # a leg's object may have been joined into another as its duplicate: it lives on there
        joined = {m: o for o in final.values() for m in o.merged_ids}
        true_pos = np.array([t.pos_ned for t in self.ctx.scenario.world.targets], dtype=float).reshape(-1, 3)
        per_object = []
        false_legs = 0
        for leg in self.legs:
            obj = final.get(leg["object_id"], joined.get(leg["object_id"]))
            near = (obj is not None and len(true_pos)
                    and float(np.min(np.linalg.norm(true_pos[:, :2] - np.asarray(obj.pos_ned)[:2], axis=1))) <= FALSE_RADIUS_M)
            leg["object_ends_false"] = not near
            false_legs += int(not near)
        for oid, obj in sorted(final.items()):
            record = g.planner.looks.get(oid)
            per_object.append(dict(
                id=oid, class_name=obj.class_name, detections=int(obj.n_detections),
                confirmed=g.planner.confirmed(obj), in_area=g.planner.in_area(obj),
                confident=g.planner.confident(obj),
                not_confident_because=g.planner.reasons(obj) if g.planner.confirmed(obj) else [],
                inspection_legs=sum(1 for leg in self.legs if leg["object_id"] == oid),
                aspects=0 if record is None else len(record.aspects),
                closest_look_m=None if record is None else round(min(v[1] for v in record.aspects), 2),
                wm_2sigma_m=round(semi_major_2sigma_m(obj.cov_ned[:2, :2]), 4),
                look_2sigma_m=round(g.planner.look_2sigma_m(obj), 4)))
        coverage_done = next((e.t_s for e in g.events if e.event == "coverage_done"), None)
        rnd = (lambda v: None if v is None else round(float(v), 2))
        breaks = [e for e in g.events if e.event in ("break_off", "resume")]
        metrics["inspection"] = dict(
            mode=cfg.mode, coverage_legs=int(g.plan.n_legs), coverage_spacing_m=rnd(g.coverage_spacing_m),
            coverage_path_m=round(g.plan.path_length_m(), 2),
            coverage_done_t_s=rnd(coverage_done), time_to_confident_map_s=rnd(g.confident_t_s),
            end_reason=next((e.event for e in reversed(g.events) if e.event not in ("done", "leg_dropped")), None),
            legs_sent=len(self.legs), legs_started=sum(1 for leg in self.legs if leg.get("started")),
            legs_completed=sum(1 for leg in self.legs if leg["outcome"] == "completed"),
            legs_ended_early=sum(1 for leg in self.legs if str(leg["outcome"]).startswith("ended early")),
            break_offs=sum(1 for e in breaks if e.event == "break_off"),
            legs_at_false_objects=false_legs, objects=per_object,
            legs=[{k: v for k, v in leg.items() if k not in ("cov_before_ned", "pos_before_ned")} for leg in self.legs],
            events=[dict(t_s=round(e.t_s, 2), event=e.event, object_id=e.object_id, detail=e.detail) for e in g.events],
            note=("time_to_confident_map_s: mission time at which the planner first judged every confirmed object "
                  "in the area confident (null: never). A leg is sent when the planner aims the vehicle at an object, "
                  "started when its first waypoint is reached, completed at its end, ended early when its object turns "
                  "confident (the looks on the way sufficed, possibly before the leg started) or unconfirmed. "
                  "legs_at_false_objects: legs aimed at objects that end up false (not in the final world model, nor "
                  f"joined as a duplicate into an object of it (its merged_ids), or more than {FALSE_RADIUS_M} m from "
                  "every true object). in_area: the object lies in the survey area grown by area_margin_m (objects "
                  "beyond it are neither inspected nor waited for). Two uncertainties: look_2sigma_m is the "
                  "planner's look-geometry model (aspects and ranges of the looks; the legs shrink it and it decides confidence); wm_2sigma_m is the world model's "
                  "covariance, which also holds the navigation error shared by all looks and so grows with the "
                  "mission's navigation uncertainty even as looks are added. aspects: bearings (30 deg apart) the "
                  "object was detected from; closest_look_m: shortest ground range of a detection"))

    def map_layers(self, layers: dict[str, Any]) -> None:
        legs = [(np.asarray(leg["start_ne_m"]), np.asarray(leg["end_ne_m"]), leg["object_id"]) for leg in self.legs]
        breaks = [(e.event, e.pos_ne_m) for e in self.guidance.events if e.event in ("break_off", "resume", "coverage_done")]
        before = [(np.asarray(leg["pos_before_ned"]), np.asarray(leg["cov_before_ned"])) for leg in self.legs
                  if leg.get("cov_before_ned") is not None]
        path = list(self._phase_path)

        def draw(ax) -> None:
            from matplotlib.patches import Ellipse

            pts = np.array([[n, e] for _, n, e in path]) if path else np.zeros((0, 2))
            inspect = np.array([ph == "inspect" for ph, _, _ in path])
            if len(pts) and inspect.any():
                seg = np.where(inspect, pts[:, 0], np.nan), np.where(inspect, pts[:, 1], np.nan)
                ax.plot(seg[1], seg[0], "-", color="tab:red", lw=2.4, alpha=0.55, zorder=2.4,
                        label="path while on inspection legs")
            for k, (s, e, oid) in enumerate(legs):
                ax.annotate("", xy=(e[1], e[0]), xytext=(s[1], s[0]), zorder=2.6,
                            arrowprops=dict(arrowstyle="->", color="darkred", lw=1.0, ls=":"))
                ax.text(s[1], s[0], f"L{k + 1}", color="darkred", fontsize=6.5, zorder=2.7,
                        bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="darkred", lw=0.5))
            if legs:
                ax.plot([], [], ls=":", color="darkred", lw=1.0, label="planned legs L1, L2, ... (in order)")
            marks = {"coverage_done": ("k", "|", "coverage pass ends"), "break_off": ("tab:orange", "v", "break-off"),
                     "resume": ("tab:green", "^", "coverage resumed")}
            for kind, (color, marker, label) in marks.items():
                at = [p for ev, p in breaks if ev == kind and p is not None]
                if at:
                    ax.plot([p[1] for p in at], [p[0] for p in at], ls="none", marker=marker, color=color, ms=7,
                            zorder=2.9, label=label)
            for j, (pos, cov) in enumerate(before):
                vals, vecs = np.linalg.eigh(cov)
                ang = math.degrees(math.atan2(vecs[0, 1], vecs[1, 1]))  # x east, y north
                ax.add_patch(Ellipse((pos[1], pos[0]), 4.0 * math.sqrt(max(vals[1], 0)), 4.0 * math.sqrt(max(vals[0], 0)),
                                     angle=ang, fill=False, ls="--", color="tab:purple", lw=0.9, zorder=2.8,
                                     label="world-model 2-sigma when its leg was planned" if j == 0 else None))

        layers["overlays"].append(draw)
        if legs:
            layers["extents"].append(np.array([p for s, e, _ in legs for p in (s, e)]))

    @classmethod
    def summary_lines(cls, metrics: Mapping[str, Any]) -> list[str]:
        ins = metrics.get("inspection")
        if not ins:
            return []
        objs = ins["objects"]
        n_conf = sum(1 for o in objs if o["confirmed"] and o.get("in_area", True))
        n_ok = sum(1 for o in objs if o["confirmed"] and o.get("in_area", True) and o["confident"])
        breaks = f", {ins['break_offs']} break-off(s)" if ins.get("break_offs") else ""
        return [f"inspection ({ins['mode']}): {ins['coverage_legs']} coverage leg(s){breaks}; {ins['legs_sent']} "
                f"inspection leg(s) sent, {ins['legs_started']} started, {ins['legs_completed']} completed, "
                f"{ins['legs_ended_early']} ended early (object confident on the way), {ins['legs_at_false_objects']} "
                f"aimed at false objects; {n_ok}/{n_conf} confirmed objects in the area confident, confident map at "
                f"{_fmt(ins['time_to_confident_map_s'], '.0f', ' s')}; ended: {ins['end_reason']}"]


__all__ = ["FALSE_RADIUS_M", "InspectionFeature"]
