"""The sea trial as a mission feature: extra vehicles (the surface buoy), their sensors and
autonomy, and the acoustic link carrying detections up to the surface world model and the
surface vehicle's USBL fixes down to the AUV's navigation filter ([P000] section VII).

Files: this module, :mod:`sim.features.surface_runner` (an extra vehicle's sensors and autonomy),
:mod:`sim.comms.vehicle_link` (the link and the surface world model),
:mod:`autonomy.navigation.delayed` (late fixes). Config: ``vehicles``, ``comms``.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from autonomy.navigation.delayed import DelayedFixFilter
from sim.comms.vehicle_link import VehicleLink
from sim.events.scheduler import AUTONOMY
from sim.features.base import FeatureContext, LoopPorts, MissionFeature
from sim.outputs.json_files import with_geodetic, write_json
from sim.features.base import fmt_or_na as _fmt
from sim.events.records import PerceptionResult
from sim.features.surface_runner import SurfaceVehicleRunner
from sim.features.survey_perception import SurveyPerceptionFeature
from sim.dynamics.truth import VehicleTruth
from sim.features.perception import target_objects, world_model_metrics


class SeaTrialFeature(MissionFeature):
    """Extra vehicles, their sensors and autonomy declared as periodic events of the loop's
    clock, and, with ``comms.acoustic`` on, the link (an event of the clock's autonomy phase:
    ticked every autonomy period, after the messages of the period are delivered).

    Attributes:
        surface_vehicles: name -> :class:`sim.features.surface_runner.SurfaceVehicleRunner`.
        link: the acoustic link (None: ``comms.acoustic`` off), made at each reset.
        vehicle_contacts: (vehicle, vehicle) -> autonomy periods that ended with their hulls touching.
        nav_filter: the AUV's filter wrapped to fuse late USBL fixes (None: not wrapped).
    """

    name = "sea_trial"

    def __init__(self, ctx: FeatureContext) -> None:
        self.ctx = ctx
        self.surface_vehicles: dict[str, SurfaceVehicleRunner] = {
            name: SurfaceVehicleRunner(ctx.physics, name, cfg, ctx.seed) for name, cfg in ctx.scenario.vehicles.items()}
        self.link: VehicleLink | None = None
        self.vehicle_contacts: Counter[tuple[str, str]] = Counter()
        self.nav_filter: DelayedFixFilter | None = None
        self._perception_feature = ctx.features.get(SurveyPerceptionFeature)

    @classmethod
    def build(cls, ctx: FeatureContext) -> SeaTrialFeature | None:
        return cls(ctx) if ctx.scenario.vehicles else None

    @property
    def _perception(self):
        return self._perception_feature.perception if self._perception_feature is not None else None

    # -- the loop ------------------------------------------------------------------------
    def wrap_nav_filter(self, nav_filter: Any) -> Any:
        surface = self.ctx.scenario.comms.surface
        self.nav_filter = None
        if self.ctx.scenario.comms.acoustic.enabled and surface.usbl_fixes and surface.fuse_usbl_fixes:
            self.nav_filter = DelayedFixFilter(nav_filter, snapshot_every_s=0.25,
                                               gate_chi2=self.ctx.scenario.autonomy.navigation.gps_gate_chi2)
            return self.nav_filter
        return nav_filter

    def reset(self, ports: LoopPorts) -> None:
        self._ports = ports
        scn = self.ctx.scenario
        for runner in self.surface_vehicles.values():
            runner.reset()
            # its sensors and autonomy on the loop's clock, at the autonomy ticks (first at t = 0)
            for name, rate_hz, event in runner.periodic_events():
                ports.every(name, rate_hz, event, stage="surface_vehicles")
        self.link = None
        if scn.comms.acoustic.enabled:  # a fresh channel and surface world model
            perception = self._perception
            self.link = VehicleLink(scn, self.surface_vehicles[scn.comms.surface.vehicle],
                                    None if perception is None else perception.pmha,
                                    None if perception is None else perception.region_ned,
                                    () if perception is None else perception.class_names, self.ctx.seed,
                                    footprint=None if perception is None else perception.sonar_footprint())
            ports.on_result(PerceptionResult, self._send_detections)
            # the link's slots on the loop's clock: every autonomy period, once its messages
            # (and so its detections) are delivered
            ports.every("comms/acoustic_link", ports.autonomy_rate_hz, self._link_tick, stage="link", phase=AUTONOMY)
        self.vehicle_contacts = Counter()

    def _send_detections(self, name: str, result: PerceptionResult) -> None:
        # the detections go to the AUV's modem (not those taken idle at the surface, unless asked)
        if self._ports.mode != "idle" or self.ctx.scenario.comms.surface.send_while_idle:
            with self._ports.timer.stage("link"):
                self.link.send_detections(self._ports.t_s, result.localized)

    def after_physics(self, t_s: float, truth: VehicleTruth) -> None:
        with self._ports.timer.stage("surface_vehicles"):  # every period ends with a contact check
            for pair in self.ctx.physics.vehicles_in_contact():
                self.vehicle_contacts[pair] += 1

    def _link_tick(self, truth: VehicleTruth) -> None:
        t_s = truth.t_s
        timer = self._ports.timer
        with timer.stage("link"):
            fixes = self.link.tick(t_s, truth, self._ports.others[self.link.node], timer)
        if self.nav_filter is not None:
            with timer.stage("nav_late_fix"):  # the re-processing is the link's cost
                for fix in fixes:
                    self.nav_filter.on_late_fix(fix)
        with timer.stage("observers"):
            for fix in fixes:
                self._ports.emit(fix.source, fix)

    def finish(self, t_s: float) -> None:
        if self.link is not None:
            self.link.finish(t_s)

    # -- a run's outputs -------------------------------------------------------------------
    def add_metrics(self, metrics: dict[str, Any], log: Any) -> None:
        others = log.other_paths_ned()
        if others:
            t_auv, p_auv, t_others = log.t_s, log.true_pos_ned, log.other_paths_t_s()
            auv = np.column_stack([np.interp(t_others, t_auv, p_auv[:, k]) for k in range(3)])
            metrics["vehicles"] = {
                "contact_periods": {"-".join(pair): n for pair, n in self.vehicle_contacts.items()},
                "min_separation_m": {name: float(np.min(np.linalg.norm(path - auv, axis=1)))
                                     for name, path in others.items()},
                "note": "contact periods: autonomy periods ending with hulls touching (every period checked); "
                        "least separation of the body origins, sampled once a second",
            }
        if self.link is None:
            return
        metrics["link"] = self.link.metrics()
        if self.nav_filter is not None:
            metrics["link"]["usbl_fixes_fused"] = self.nav_filter.n_late_fused
            metrics["link"]["usbl_fixes_refused"] = self.nav_filter.n_late_gated + self.nav_filter.n_late_too_old
        surface = self.link.surface_world_model
        perception = self._perception_feature.results() if self._perception_feature is not None else None
        if surface is not None and perception is not None:
            sw = world_model_metrics(surface.world_model(), perception.truth_targets)
            sw["world_model_json_objects"] = len(surface.world_model())
            sw["note"] = ("the world model on the surface vehicle, from the detections the acoustic link delivered "
                          "(surface_world_model.json); scored as world_model")
            metrics["surface_world_model"] = sw

    def map_layers(self, layers: dict[str, Any]) -> None:
        if self.link is not None and self.link.surface_world_model is not None:
            layers["surface_estimates_ned"] = [o.pos_ned for o in
                                               target_objects(self.link.surface_world_model.world_model())]

    def write_outputs(self, out_dir: Path, metrics: dict[str, Any], title: str) -> None:
        if self.link is not None and self.link.surface_world_model is not None:
            write_json(out_dir / "surface_world_model.json",
                       with_geodetic(self.link.surface_world_model.to_json(), self.ctx.scenario.world.origin))

    @classmethod
    def summary_lines(cls, metrics: Mapping[str, Any]) -> list[str]:
        lines = []
        if "surface_world_model" in metrics:
            wm = metrics["surface_world_model"]
            lines.append(f"surface world model: {wm['objects']} targets, {wm['matched']} matched, {wm['missed']} "
                         f"missed, {wm['false']} false, mean error {_fmt(wm.get('mean_position_error_m'), '.2f', ' m')}")
        if "link" not in metrics:
            return lines
        link = metrics["link"]
        up, down = link["uplink_detections"], link["downlink_usbl_fixes"]
        for name, st in (("detections up", up), ("USBL fixes down", down)):
            pending = f", {st['pending']} still queued or in flight at the end" if st.get("pending") else ""
            lines.append(f"link, {name}: {st['sent']} sent, {st['delivered']} delivered, {st['lost']} lost{pending}, "
                         f"latency mean {_fmt(st.get('mean_latency_s'), '.2f', ' s')}, "
                         f"p95 {_fmt(st.get('p95_latency_s'), '.2f', ' s')}")
        held = link.get("usbl_fixes_superseded", 0) + link.get("usbl_fixes_unsent_at_end", 0)
        if held:
            reach = link.get("tdma", {}).get("surface_reach_m")
            lines.append(f"link: {held} of {link.get('usbl_fixes_made', 0)} USBL fixes not sent: each waited for a "
                         f"surface slot it fitted, packet and travel time, until a newer fix replaced it (the slot "
                         f"carries a fix to {_fmt(reach, '.0f', ' m')}; a longer comms.surface.surface_slot_s reaches "
                         "farther)")
        if link.get("unencodable"):
            lines.append(f"link: {link['unencodable']} messages not sent: a value outside its field in message_version "
                         f"{link.get('message_version')}")
        return lines
