"""Load-time checks of the acoustic link's messages and slots against the scenario.

Run at load (:func:`scenarios.load.check_scenario`) when ``comms.acoustic.enabled``, so a
scenario whose vehicles could produce a value the wire format cannot hold, or whose slots
cannot carry a packet at all, is refused with one line naming the keys instead of failing
at the first message of the run.

Message fields (:mod:`autonomy.comms.wire`) and what bounds them:

- depth: the field of ``comms.surface.message_version`` (:func:`autonomy.comms.wire.depth_range_m`)
  against the depths the mission can encode: from the surface (minus 1 m, the start above
  it that placement allows) to the deepest of the seabed (its mean plane's deepest point
  over the patch, or a bathymetry file's deepest cell, plus the relief of a rough or
  rippled bed) and ``autonomy.guidance.mission.safe_depth_max_m`` (outside the patch the
  mission's depth abort bounds the AUV), widened by the USBL fix's error there: its
  outlier range excess plus 4 range sigmas at that depth, the depth error of a fix taken
  from above (:class:`scenarios.config.usbl.UsblConfig`). A rarer fix beyond that (an
  outlier's wild elevation) is not sent and is counted (``link.unencodable``).
- time (u32 UNIX seconds): ``comms.surface.epoch_unix_s`` (to 2100) plus ``duration_s``
  (to one day) ends before 2106 for every scenario the schema allows.
- latitude / longitude (i32, 1e-7 deg): every position maps into [-90, 90] and
  [-180, 180] deg (:mod:`autonomy.geodesy` wraps the longitude).
- ids wrap at 65536. Covariance sigmas (u16 mm) beyond 65.535 m (a USBL fix from about
  570 m off with the default head) would saturate and understate the error: such a message
  is not sent and is counted (``link.unencodable``). Class ids (u8) index the detector's
  table, known once the detector is built.

Slots (:mod:`autonomy.comms.tdma`): each slot in use must carry its packet (a USBL fix in
the surface vehicle's, a detection in the AUV's) at least at zero range: duration plus
``comms.acoustic.multipath_max_delay_s`` plus ``comms.surface.guard_s`` within the slot.
Farther, a slot carries its packet to its reach (``metrics.json`` ``link.tdma``); a packet
that does not fit at the current range waits for a slot where it does.
"""

from __future__ import annotations

import math

import numpy as np

from autonomy.comms import wire
from autonomy.comms.messages import DETECTION_TYPE, USBL_FIX_TYPE, message_size_bytes
from scenarios.schema import Scenario
from scenarios.bathymetry import BathymetryError, read_depth_grid

#: Range sigmas of a USBL fix's error allowed for in the depth envelope.
USBL_SIGMAS = 4.0
#: How far above the surface (negative depth) the AUV may be, m (placement's start limit).
ABOVE_SURFACE_M = 1.0


def deepest_seabed_m(scenario: Scenario) -> tuple[float, str]:
    """Deepest point of the seabed (NED z, m) and the key it comes from.

    Plane or slope: the mean plane's deepest corner of the patch (``world.seabed.extent_m``
    about ``center_ne_m``) plus the relief of a rough or rippled bed; file: the grid's
    deepest valid cell (NaN when the file cannot be read: its own check reports it).
    """
    from scenarios.placement import seabed_mean_depth_m, seabed_relief_m

    c = scenario.world.seabed
    if c.kind == "file":
        try:
            grid = read_depth_grid(c.file)
        except BathymetryError:
            return math.nan, "world.seabed.file"
        return float(np.nanmax(grid.depth_m)), "world.seabed.file"
    half = 0.5 * c.extent_m
    n0, e0 = c.center_ne_m
    corners = [seabed_mean_depth_m(scenario, n0 + sn * half, e0 + se * half) for sn in (-1, 1) for se in (-1, 1)]
    key = "world.seabed.depth_m" if c.kind == "plane" or c.slope_deg == 0.0 else \
        "world.seabed.depth_m, slope_deg and extent_m"
    return max(corners) + seabed_relief_m(scenario), key


def depth_envelope_m(scenario: Scenario) -> tuple[float, float, str]:
    """(shallowest, deepest) depth (m) the mission's messages can carry, and the keys the
    deepest comes from (see the module docstring)."""
    bed_m, bed_key = deepest_seabed_m(scenario)
    abort_m = scenario.autonomy.guidance.mission.safe_depth_max_m
    deepest, key = (bed_m, bed_key) if not bed_m < abort_m else (abort_m, "autonomy.guidance.mission.safe_depth_max_m")
    if not math.isfinite(deepest):
        deepest, key = abort_m, "autonomy.guidance.mission.safe_depth_max_m"
    usbl = scenario.vehicles[scenario.comms.surface.vehicle].usbl if scenario.comms.surface.vehicle in \
        scenario.vehicles else None
    margin = 0.0
    if usbl is not None and scenario.comms.surface.usbl_fixes:
        margin = usbl.outlier_extra_range_m + USBL_SIGMAS * usbl.range_sigma_at(deepest)
        key += f" plus {margin:.1f} m for the USBL fix's error"
    return -(ABOVE_SURFACE_M + margin), deepest + margin, key


def comms_problems(scenario: Scenario) -> list[str]:
    """Problems of the acoustic link's message fields and slots, one line each (none when
    the link is off)."""
    acoustic, surface = scenario.comms.acoustic, scenario.comms.surface
    if not acoustic.enabled:
        return []
    problems = []
    version = surface.message_version
    lo, hi = wire.depth_range_m(version)
    shallow_m, deep_m, key = depth_envelope_m(scenario)
    if not lo <= shallow_m <= deep_m <= hi:
        wider = [v for v in wire.VERSIONS if v > version]
        hint = (f"; message_version {wider[-1]} carries {wire.depth_range_m(wider[-1])[1]:.2f} m" if wider
                else "; a shallower scene")
        problems.append(f"comms.surface.message_version: version {version} carries depths {lo:g} to {hi:g} m, and "
                        f"this scenario's messages can reach {deep_m:.1f} m ({key}){hint}")
    mp_guard = acoustic.multipath_max_delay_s + surface.guard_s
    for on, name, msg_type, slot_s, slot_key in (
            (surface.usbl_fixes, "a USBL fix", USBL_FIX_TYPE, surface.surface_slot_s, "comms.surface.surface_slot_s"),
            (surface.detections, "a detection report", DETECTION_TYPE, surface.cycle_s - surface.surface_slot_s,
             "comms.surface.cycle_s minus surface_slot_s")):
        if not on:
            continue
        d = acoustic.packet_duration_s(message_size_bytes(msg_type, version))
        if d + mp_guard > slot_s:
            problems.append(f"{slot_key}: the {slot_s:g} s slot cannot carry {name} even at zero range: it lasts "
                            f"{d:.3f} s at comms.acoustic.bit_rate_bps {acoustic.bit_rate_bps:g}, plus "
                            f"comms.acoustic.multipath_max_delay_s {acoustic.multipath_max_delay_s:g} s and "
                            f"comms.surface.guard_s {surface.guard_s:g} s (needs {d + mp_guard:.3f} s)")
    return problems
