"""The acoustic link between the AUV and the surface vehicle in a mission (paper 000
section VII, docs/references.md [P000]).

:class:`VehicleLink` is what the mission loop ticks when ``comms.acoustic`` is on. Up: each
sonar frame's geolocated detections, fused per object as the PMHA fuses a scan's duplicate
boxes (:meth:`autonomy.world_model.PMHA.cluster_scan`), are encoded as detection reports
(:class:`autonomy.comms.messages.DetectionReport`: id, absolute time, latitude / longitude /
depth from the AUV's navigation, covariance summary, class and reliability) and queued at
the AUV's modem; what arrives feeds the surface world model
(:class:`autonomy.world_model.surface.SurfaceWorldModel`). Down: the surface vehicle's
newest USBL fix of the AUV (:class:`sim.features.surface_runner.SurfaceVehicleRunner`) is encoded as
a USBL-fix report and sent in its slot; what arrives becomes a
:class:`autonomy.messages.PositionFixMsg` stamped with the measurement time, for the AUV's
navigation filter to fuse at that time (:class:`autonomy.navigation.delayed.DelayedFixFilter`).
Medium access is the time-division cycle of :mod:`autonomy.comms.tdma`: a packet is released
only when it, its travel time to the other vehicle (the range at the release tick over the
sound speed, plus the channel's longest multipath delay) and ``comms.surface.guard_s`` end in
its sender's slot. The range is the vehicles' true one; on the water the buoy measures it
with each USBL fix and the AUV reads it from the two positions in each fix report, and the
guard covers the difference (0.05 s is 75 m).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from autonomy.comms.messages import (
    DETECTION_TYPE,
    USBL_FIX_TYPE,
    DetectionReport,
    UsblFixReport,
    decode,
    message_size_bytes,
)
from autonomy.comms.tdma import AUV, SURFACE, SlotSender, TdmaSchedule
from autonomy.geodesy import ned_to_lat_lon_depth
from autonomy.localization.geolocate import LocalizedDetection
from autonomy.messages import PositionFixMsg
from autonomy.world_model import PMHA
from autonomy.world_model.surface import FixTrack, SonarFootprint, SurfaceWorldModel
from scenarios.schema import Scenario
from sim.comms.acoustic_link import AcousticLink
from sim.events.stage_timer import NULL_TIMER, StageTimer
from sim.dynamics.truth import VehicleTruth

if TYPE_CHECKING:  # the link reads the runner's fixes; the runner lives with the sea-trial feature
    from sim.features.surface_runner import SurfaceVehicleRunner

AUV_NODE = "auv"
#: Link-level source name of the fixes handed to the navigation filter.
FIX_SOURCE = "surface_usbl"


class VehicleLink:
    """Detections up, USBL fixes down, over one seeded acoustic link.

    Args:
        scenario: the scenario (``comms.acoustic``, ``comms.surface``, ``world.origin``,
            ``autonomy.world_model``).
        surface: the surface vehicle's runner (its USBL fixes of the AUV).
        onboard_pmha: the AUV's world model (its scan clustering; None: detections are sent
            as they are).
        region_ned: the surveyed volume of the surface world model (as the onboard one's).
        class_names: the ATR's class table (the reports' class ids index it on both ends).
        footprint: the AUV's sonar as the surface knows it (None: the surface world model
            uses the visibility floor for every anchor).
        seed: root seed (the link draws from ``component_rng(seed, "acoustic_link")``).

    Attributes:
        link: the channel.
        surface_world_model: the world model on the surface (None when detections are not sent).
        n_detections_queued, n_fixes_queued, n_fixes_received: counters.
        n_unencodable: messages not sent because a value lies outside its field in
            ``comms.surface.message_version`` (a USBL outlier beyond the depth range the
            scenario was checked for at load, :mod:`scenarios.comms_checks`, or a sigma
            beyond 65.535 m: a USBL fix from far off).
    """

    def __init__(self, scenario: Scenario, surface: SurfaceVehicleRunner, onboard_pmha: PMHA | None,
                 region_ned: tuple[Any, Any] | None, class_names: Sequence[str], seed: int,
                 footprint: SonarFootprint | None = None) -> None:
        comms = scenario.comms
        self.cfg, self.acoustic = comms.surface, comms.acoustic
        self.origin = scenario.world.origin
        self.surface = surface
        self.node = surface.name
        self.link = AcousticLink.from_config(self.acoustic, [AUV_NODE, self.node], seed)
        self.schedule = TdmaSchedule(self.cfg.cycle_s, self.cfg.surface_slot_s, self.cfg.guard_s)
        self._up = SlotSender(self.schedule, AUV, self.cfg.max_detection_age_s)
        self._down = SlotSender(self.schedule, SURFACE)
        self.version = self.cfg.message_version
        self._onboard_pmha = onboard_pmha
        self.class_names = tuple(class_names)
        self.surface_world_model = None
        #: The AUV's track from the surface vehicle's own USBL fixes (places the sonar's fan).
        self.auv_track = FixTrack()
        if self.cfg.detections and region_ned is not None:
            self.surface_world_model = SurfaceWorldModel(scenario.autonomy.world_model, region_ned, self.origin,
                                                         self.cfg.epoch_unix_s, self.class_names,
                                                         footprint=footprint, track=self.auv_track)
        self._det_id = self._fix_id = 0
        self.n_detections_queued = self.n_fixes_queued = self.n_fixes_received = self.n_unencodable = 0

    def _encode(self, msg: DetectionReport | UsblFixReport) -> bytes | None:
        """The packet of ``msg`` in the configured version, or None (counted) when a value
        does not fit its field (a sigma beyond the covariance field included: saturated, it
        would make the receiver overconfident)."""
        try:
            return msg.encode(self.version, saturate=False)
        except ValueError:
            self.n_unencodable += 1
            return None

    # ------------------------------------------------------------------ AUV side
    def send_detections(self, t_s: float, localized: Sequence[LocalizedDetection]) -> None:
        """Queue one frame's geolocated detections (mission frame, NED) at the AUV's modem
        (the mission leaves out those taken idle at the surface, ``comms.surface.send_while_idle``)."""
        if not self.cfg.detections or not localized:
            return
        scan = self._onboard_pmha.cluster_scan(localized) if self._onboard_pmha is not None else list(localized)
        for det in scan:
            report = DetectionReport.from_localized(det, self._det_id, self.origin, self.cfg.epoch_unix_s,
                                                    self.class_names)
            self._det_id = (self._det_id + 1) % 65536
            packet = self._encode(report)
            if packet is not None:
                self._up.put(t_s, packet)
                self.n_detections_queued += 1

    # ------------------------------------------------------------------ the tick
    def tick(self, t_s: float, auv: VehicleTruth, surface: VehicleTruth, timer: StageTimer | None = None) -> list[PositionFixMsg]:
        """Run the link up to ``t_s`` with the two vehicles' true states (positions and
        speeds for the channel); returns the USBL fixes the AUV received, stamped with their
        measurement time (mission s). The surface world model's update is timed as stage
        ``surface_world_model`` of ``timer``."""
        fixes = self.surface.take_auv_fixes()
        for f in fixes:
            self.auv_track.add(f.t_s, f.pos_ned)
        if self.cfg.usbl_fixes:
            if fixes:
                f = fixes[-1]
                lat, lon, depth = (float(v) for v in ned_to_lat_lon_depth(f.pos_ned, self.origin))
                blat, blon, _ = ned_to_lat_lon_depth(f.vessel_pos_ned, self.origin)
                report = UsblFixReport(self._fix_id, self.cfg.epoch_unix_s + f.t_s, lat, lon, depth, f.cov_ned,
                                       float(blat), float(blon))
                self._fix_id = (self._fix_id + 1) % 65536
                packet = self._encode(report)
                if packet is not None:
                    self._down.replace(t_s, packet)
                    self.n_fixes_queued += 1
        duration = self.acoustic.packet_duration_s
        range_m = float(np.linalg.norm(np.asarray(auv.pos_ned, float) - np.asarray(surface.pos_ned, float)))
        travel_s = self.travel_s(range_m)
        for payload in self._up.release(t_s, duration, travel_s):
            self.link.send(t_s, AUV_NODE, self.node, payload)
        for payload in self._down.release(t_s, duration, travel_s):
            self.link.send(t_s, self.node, AUV_NODE, payload)
        self.link.advance(t_s, {AUV_NODE: auv.pos_ned, self.node: surface.pos_ned},
                          {AUV_NODE: float(np.linalg.norm(auv.nu[:3])), self.node: float(np.linalg.norm(surface.nu[:3]))})
        timer = NULL_TIMER if timer is None else timer
        wm = self.surface_world_model
        for pkt in self.link.delivered(t_s, dst=self.node):
            msg = decode(pkt.payload)
            if wm is not None and isinstance(msg, DetectionReport):
                wm.receive(msg)
        if wm is not None:
            with timer.stage("surface_world_model"):
                wm.flush(t_s)
        out = []
        for pkt in self.link.delivered(t_s, dst=AUV_NODE):
            msg = decode(pkt.payload)
            if isinstance(msg, UsblFixReport):
                self.n_fixes_received += 1
                pos = msg.pos_ned(self.origin)
                out.append(PositionFixMsg(msg.t_unix_s - self.cfg.epoch_unix_s, pos[:2],
                                          np.asarray(msg.cov_ned, dtype=float)[:2, :2], source=FIX_SOURCE))
        return out

    def travel_s(self, range_m: float) -> float:
        """Longest time a packet takes to reach the other vehicle at ``range_m`` (m): range /
        sound speed plus the longest multipath delay, s (what the slots must leave room for)."""
        return range_m / self.acoustic.sound_speed_mps + self.acoustic.multipath_max_delay_s

    def reach_m(self) -> dict[str, float]:
        """Farthest range (m) to which each slot carries its packet
        (:meth:`autonomy.comms.tdma.TdmaSchedule.reach_m`): ``surface_reach_m`` for a USBL
        fix, ``auv_reach_m`` for a detection report."""
        a = self.acoustic
        out = {}
        for key, node, msg_type in (("surface_reach_m", SURFACE, USBL_FIX_TYPE), ("auv_reach_m", AUV, DETECTION_TYPE)):
            d = a.packet_duration_s(message_size_bytes(msg_type, self.version))
            out[key] = self.schedule.reach_m(node, d, a.sound_speed_mps, a.multipath_max_delay_s)
        return out

    def finish(self, t_s: float) -> None:
        """End of the mission: the surface world model processes every scan it holds."""
        if self.surface_world_model is not None:
            self.surface_world_model.flush(t_s, final=True)

    def metrics(self) -> dict[str, Any]:
        """Link statistics (messages sent, delivered, lost, mean and p95 latency) per
        direction and overall, and the application counters."""
        up, down = self.link.stats(AUV_NODE, self.node), self.link.stats(self.node, AUV_NODE)
        out: dict[str, Any] = {
            "uplink_detections": up.to_dict(), "downlink_usbl_fixes": down.to_dict(),
            "all": self.link.stats().to_dict(),
            "detections_queued": self.n_detections_queued,
            "detections_dropped_stale": self._up.n_dropped_stale,
            "detections_unsent_at_end": len(self._up),  # queued = sent + dropped stale + these
            "unencodable": self.n_unencodable,  # values outside their field: not queued
            "message_version": self.version,
            "usbl_fixes_made": self.n_fixes_queued, "usbl_fixes_received": self.n_fixes_received,
            # made = sent + superseded (a newer fix came before it fitted its slot) + unsent at the end
            "usbl_fixes_superseded": self._down.n_superseded, "usbl_fixes_unsent_at_end": len(self._down),
            "tdma": {"cycle_s": self.cfg.cycle_s, "surface_slot_s": self.cfg.surface_slot_s,
                     "guard_s": self.cfg.guard_s, **self.reach_m()},
        }
        wm = self.surface_world_model
        if wm is not None:
            out["surface_world_model"] = {"reports_received": wm.n_reports, "scans": wm.n_scans,
                                          "reports_too_late": wm.n_too_late}
        return out
