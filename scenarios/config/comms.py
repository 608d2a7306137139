"""Communication channels between the scene's vehicles: the acoustic modem link.

The link is not a sensor: it is not sampled at a rate on one hull but carries messages
between several nodes, one event at a time. It gets its own ``comms:`` section
(``comms: {acoustic: {enabled: true, ...}}``); the simulator is :class:`sim.comms.AcousticLink`.
"""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field, model_validator

from scenarios.config.base import NonNegFloat, Probability, StrictModel


class AcousticLinkConfig(StrictModel):
    """A half-duplex acoustic modem link (paper 000 section VII: EvoLogics S2CR 18/34 modems,
    docs/references.md [P000], [S2CR1834], [ModemRates]).

    Timing: a packet of ``n`` payload bytes lasts ``(n + overhead_bytes) * 8 / bit_rate_bps``
    and arrives ``range / sound_speed_mps`` after it was sent (plus a multipath delay).

    Loss: a packet sent over range ``r`` between nodes moving at ``v_src`` and ``v_dst``
    (m/s) is delivered with probability

        (1 - p_range(r)) * (1 - p_noise(v_src)) * (1 - p_noise(v_dst)),
        p_range(r) = loss_near + (loss_far - loss_near) / (1 + exp(-(r - loss_range50_m) / loss_range_width_m)),
        p_noise(v) = min(noise_loss_per_mps * v, 1),

    a logistic fall-off with range (signal below the detection threshold) and a self-noise
    term for a node under way (thrusters and flow noise mask the receiver; the sender's own
    motion adds Doppler spread). Beyond that, a packet is lost when its receiver transmits
    while it arrives (half duplex) or when two arrivals overlap at the receiver (collision).

    Defaults (our estimates for the S2CR 18/34 class in a harbour basin, not datasheet
    values): 1000 bit/s effective (the S2CR 18/34's acoustic rate is up to 13.9 kbit/s; robust
    telemetry runs at 100 bit/s to a few kbit/s), 16 bytes of framing per packet, 3.5 km
    nominal range (the datasheet's) taken as the 50 % loss point, 2 % loss at short range,
    5 % per m/s of each end's speed, 5 % multipath outliers up to 50 ms (75 m of extra path).
    """

    enabled: bool = Field(False, description="build the link (the mission integrates it when on)")
    bit_rate_bps: float = Field(1000.0, ge=50.0, le=20000.0, description="effective acoustic bit rate, bit/s")
    overhead_bytes: int = Field(16, ge=0, le=1024, description="preamble, addressing and coding per packet, bytes")
    max_payload_bytes: int = Field(64, ge=1, le=65535, description="largest payload of one packet, bytes")
    sound_speed_mps: float = Field(1500.0, ge=1400.0, le=1600.0)
    queue_limit: int = Field(32, ge=1, le=100_000, description="packets a node's send queue holds; more are dropped")
    loss_near: Probability = Field(0.02, description="loss probability at short range")
    loss_far: Probability = Field(1.0, description="loss probability far beyond loss_range50_m")
    loss_range50_m: float = Field(3500.0, gt=0.0, le=100_000.0, description="range of the logistic's midpoint, m")
    loss_range_width_m: float = Field(400.0, gt=0.0, le=50_000.0, description="logistic scale, m")
    noise_loss_per_mps: NonNegFloat = Field(0.05, le=10.0, description="loss probability per m/s of each end's speed")
    multipath_prob: Probability = Field(0.05, description="probability that a packet arrives by a longer path")
    multipath_max_delay_s: NonNegFloat = Field(0.05, le=10.0, description="extra delay of such a packet: U(0, this), s")

    @model_validator(mode="after")
    def _loss_order(self) -> "AcousticLinkConfig":
        if self.loss_far < self.loss_near:
            raise ValueError(f"comms.acoustic.loss_far ({self.loss_far}) must be >= loss_near ({self.loss_near})")
        return self

    def packet_duration_s(self, payload_bytes: int) -> float:
        """Time on the water of a packet of ``payload_bytes``: (payload + overhead) * 8 / rate, s."""
        return (payload_bytes + self.overhead_bytes) * 8.0 / self.bit_rate_bps

    def range_loss_prob(self, range_m: float) -> float:
        """p_range(r): the logistic loss probability at ``range_m`` (m) of a node at rest."""
        z = (range_m - self.loss_range50_m) / self.loss_range_width_m
        s = 1.0 / (1.0 + math.exp(-z)) if z > -700.0 else 0.0
        return self.loss_near + (self.loss_far - self.loss_near) * s

    def noise_loss_prob(self, speed_mps: float) -> float:
        """p_noise(v): the self-noise loss probability of one end moving at ``speed_mps``."""
        return min(self.noise_loss_per_mps * max(speed_mps, 0.0), 1.0)

    def delivery_prob(self, range_m: float, speed_src_mps: float = 0.0, speed_dst_mps: float = 0.0) -> float:
        """Probability that the channel delivers a packet (half duplex and collisions aside)."""
        return ((1.0 - self.range_loss_prob(range_m)) * (1.0 - self.noise_loss_prob(speed_src_mps))
                * (1.0 - self.noise_loss_prob(speed_dst_mps)))


class SurfaceLinkConfig(StrictModel):
    """What the AUV and the surface vehicle exchange over the acoustic link (paper 000
    section VII, docs/references.md [P000]): the AUV sends each geolocated detection up, the
    surface vehicle runs its own world model on what arrives and sends its USBL fixes of
    the AUV down, which the AUV's navigation filter fuses at their measurement time.

    Medium access is a fixed time-division cycle of ``cycle_s``: the surface vehicle talks
    in the first ``surface_slot_s`` of each cycle (its latest USBL fix), the AUV in the rest
    (its queued detections, one packet at a time, only when the packet, its travel time and
    ``guard_s`` end before the next surface slot). The travel time is the range over the
    sound speed plus ``comms.acoustic.multipath_max_delay_s``, so a slot of ``L`` s carries a
    packet of ``d`` s to ``sound_speed * (L - d - guard_s - multipath_max_delay_s)`` (the
    slot's reach, in ``metrics.json``); farther, the packet waits. Half-duplex modems then
    never talk over each other; losses are the channel's.

    Messages are written in ``message_version`` (:mod:`autonomy.comms.messages`): 2 carries
    depths to 83.9 km, 1 (for receivers that read only it) to 327.67 m; a scenario that could
    produce a value its version cannot hold is refused at load (:mod:`scenarios.comms_checks`).
    """

    vehicle: str = Field("buoy", min_length=1, description="the surface vehicle (a key of vehicles:)")
    detections: bool = Field(True, description="send the AUV's detections up")
    send_while_idle: bool = Field(
        False, description="also send the detections taken before the mission starts (at rest at the surface, "
        "where the surface vehicle cannot tell which way the sonar looks)")
    usbl_fixes: bool = Field(True, description="send the surface vehicle's USBL fixes of the AUV down")
    fuse_usbl_fixes: bool = Field(True, description="the AUV's navigation filter fuses the fixes it receives")
    cycle_s: float = Field(2.0, gt=0.2, le=600.0, description="time-division cycle, s")
    surface_slot_s: float = Field(0.6, gt=0.0, le=600.0, description="surface vehicle's slot at each cycle's start, s")
    guard_s: float = Field(0.05, ge=0.0, le=10.0,
                           description="margin after a packet's arrival (travel and multipath delay included) "
                           "before the other slot, s")
    message_version: Literal[1, 2] = Field(
        2, description="protocol version of the messages sent (2: depth to 83.9 km; 1: to 327.67 m, for "
        "receivers that read only version 1); both are decoded")
    max_detection_age_s: float = Field(30.0, gt=0.0, le=3600.0,
                                       description="queued detections older than this are dropped unsent, s")
    epoch_unix_s: float = Field(1_688_169_600.0, ge=0.0, le=4_102_444_800.0,
                                description="UNIX time of mission time 0 (messages carry absolute time), s")

    @model_validator(mode="after")
    def _slot_fits(self) -> "SurfaceLinkConfig":
        if self.surface_slot_s >= self.cycle_s:
            raise ValueError(f"comms.surface.surface_slot_s ({self.surface_slot_s}) must be shorter than "
                             f"cycle_s ({self.cycle_s})")
        return self


class CommsConfig(StrictModel):
    """Communication channels of the scene (``comms:``); every one is off by default."""

    acoustic: AcousticLinkConfig = AcousticLinkConfig()
    surface: SurfaceLinkConfig = SurfaceLinkConfig()
