"""Mechanically scanned imaging sonar config (Blue Robotics Ping360 class, [P002], [Ping360]).

Device settings are the device's own: ``range_m`` with ``number_of_samples`` set the sample
period (ticks of 25 ns, at least 80), ``transmit_duration_us`` (5-500 us, at most 64 sample
periods; ``None``: the device software's automatic value), ``step_grad`` (1-10 gradians per
ping) and the sector (``sector_width_grad`` up to 400 = a full turn; a narrower sector is swept
back and forth about ``sector_centre_grad``). The ping rate follows from them
(:func:`autonomy.msis.ping360.ping_duration_s`); ``rate_hz`` is not set by hand. Head angle 0
is the mount's boresight, angles grow clockwise seen from above (to starboard).
Acoustic constants marked "estimate" are ours, not datasheet.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from autonomy.msis import ping360
from scenarios.config.base import Vec3
from scenarios.config.sensor import SensorConfig, sensor_config


@sensor_config
class MsisConfig(SensorConfig):
    """Ping360-class scanning sonar: device settings, beam, timing model, image formation."""

    kind: Literal["msis"] = "msis"

    rate_hz: float | None = Field(None, description="leave unset: the ping rate follows from the device timing")
    latency_s: float = Field(0.01, ge=0.0, le=5.0, description="ping to delivery, s")
    mount_pos_body_m: Vec3 | None = Field((0.1, 0.0, -0.2), description="FRD offset of the head, m (estimate: "
                                          "on top of a BlueROV2 frame)")
    tilt_deg: float = Field(0.0, ge=-45.0, le=45.0, description="beam axis pitched down")

    # device settings
    range_m: float = Field(12.0, gt=0.0, le=50.0, description="one-way range, m (device maximum 50 m)")
    number_of_samples: int = Field(1200, ge=1, le=ping360.MAX_SAMPLES, description="samples per ping")
    speed_of_sound_mps: float = Field(1500.0, ge=1300.0, le=1700.0)
    transmit_duration_us: float | None = Field(
        None, ge=ping360.MIN_TRANSMIT_US, le=ping360.MAX_TRANSMIT_US, description="None: automatic")
    step_grad: int = Field(1, ge=1, le=10, description="head step per ping, gradians")
    sector_width_grad: int = Field(400, ge=1, le=ping360.GRAD_PER_TURN, description="400: full turn")
    sector_centre_grad: float = Field(0.0, ge=0.0, lt=ping360.GRAD_PER_TURN)
    motor_s_per_grad: float = Field(0.0025, ge=0.0, le=0.1, description="head step time, s per gradian (estimate)")
    overhead_s: float = Field(0.004, ge=0.0, le=1.0, description="processing and transfer per ping, s (estimate)")

    # beam
    horizontal_beamwidth_deg: float = Field(2.0, gt=0.0, le=20.0, description="-3 dB one-way")
    vertical_beamwidth_deg: float = Field(25.0, gt=0.0, le=90.0, description="-3 dB one-way")
    elevation_rays: int = Field(16, ge=2, le=256, description="rays across the vertical beam")
    azimuth_rays: int = Field(5, ge=1, le=31, description="ray columns across the horizontal beam pattern")
    edge_refine_iters: int = Field(5, ge=0, le=20)

    # image formation
    absorption_db_per_m: float = Field(0.2, ge=0.0, le=10.0, description="one-way, 750 kHz (estimate)")
    scattering_exponent: float = Field(1.0, ge=0.0, le=10.0)
    speckle: Literal["none", "rayleigh", "k"] = "rayleigh"
    k_shape: float = Field(2.0, gt=0.0, le=100.0)
    noise_floor_db: float = Field(-75.0, ge=-200.0, le=0.0, description="receiver noise before TVG (estimate)")
    tvg_spreading_db_per_decade: float = Field(20.0, ge=0.0, le=60.0)
    tvg_absorption: bool = True
    gain_db: float = Field(0.0, ge=-100.0, le=200.0)
    dynamic_range_db: float = Field(50.0, gt=1.0, le=150.0)
    scan_image_px: int = Field(400, ge=32, le=4096, description="side of the Cartesian scan image")

    @model_validator(mode="after")
    def _check_device(self) -> "MsisConfig":
        if self.rate_hz is not None:
            raise ValueError("rate_hz: leave unset, the ping rate follows from the device timing "
                             f"({self.ping_duration_s:.4f} s per ping)" if self._period_ok() else
                             "rate_hz: leave unset, the ping rate follows from the device timing")
        if self.mount_rpy_deg[1] != 0.0:
            raise ValueError("mount_rpy_deg pitch must be 0 for a sonar: set its tilt with tilt_deg")
        sp = ping360.sample_period_ticks(self.range_m, self.number_of_samples, self.speed_of_sound_mps)
        if sp < ping360.MIN_SAMPLE_PERIOD_TICKS:
            r_min = ping360.range_m(self.number_of_samples, ping360.MIN_SAMPLE_PERIOD_TICKS, self.speed_of_sound_mps)
            raise ValueError(
                f"range_m = {self.range_m:g} m with number_of_samples = {self.number_of_samples} needs a sample "
                f"period of {sp} ticks; the device needs >= {ping360.MIN_SAMPLE_PERIOD_TICKS} ticks: "
                f"range_m >= {r_min:.3f} m or fewer number_of_samples")
        if sp > ping360.MAX_SAMPLE_PERIOD_TICKS:
            raise ValueError(
                f"range_m = {self.range_m:g} m with number_of_samples = {self.number_of_samples} needs a sample "
                f"period of {sp} ticks, above the device's {ping360.MAX_SAMPLE_PERIOD_TICKS}: more samples")
        t_max = ping360.max_transmit_us(sp)
        if self.transmit_duration_us is not None and self.transmit_duration_us > t_max:
            raise ValueError(f"transmit_duration_us = {self.transmit_duration_us:g} exceeds the firmware limit "
                             f"min(500, 64 sample periods) = {t_max:g} us at a {sp}-tick sample period")
        if self.sector_width_grad < ping360.GRAD_PER_TURN and self.sector_width_grad < self.step_grad:
            raise ValueError(f"sector_width_grad = {self.sector_width_grad} must be >= step_grad = {self.step_grad}")
        return self

    def _period_ok(self) -> bool:
        sp = ping360.sample_period_ticks(self.range_m, self.number_of_samples, self.speed_of_sound_mps)
        return ping360.MIN_SAMPLE_PERIOD_TICKS <= sp <= ping360.MAX_SAMPLE_PERIOD_TICKS

    # -- derived device figures ----------------------------------------------------------
    @property
    def sample_period_ticks(self) -> int:
        """Sample period, ticks of 25 ns."""
        return ping360.sample_period_ticks(self.range_m, self.number_of_samples, self.speed_of_sound_mps)

    @property
    def sample_spacing_m(self) -> float:
        """Range between samples, m."""
        return ping360.sample_spacing_m(self.sample_period_ticks, self.speed_of_sound_mps)

    @property
    def effective_range_m(self) -> float:
        """Range the samples cover at the integer sample period, m."""
        return ping360.range_m(self.number_of_samples, self.sample_period_ticks, self.speed_of_sound_mps)

    @property
    def effective_transmit_us(self) -> float:
        """Transmit duration used, us (automatic when unset)."""
        if self.transmit_duration_us is not None:
            return float(self.transmit_duration_us)
        return ping360.auto_transmit_us(self.range_m, self.sample_period_ticks, self.speed_of_sound_mps)

    @property
    def ping_duration_s(self) -> float:
        """Time from one ping to the next, s (:func:`autonomy.msis.ping360.ping_duration_s`)."""
        return ping360.ping_duration_s(self.step_grad, self.effective_transmit_us, self.number_of_samples,
                                       self.sample_period_ticks, self.motor_s_per_grad, self.overhead_s)
