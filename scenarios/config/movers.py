"""Moving targets: a diver (with regulator bubble plumes) or a small vehicle on a mocap body.

Kinematics after paper 004 eq. (6) (docs/references.md [P004]): course, course rate, surge
and heave speed; the manoeuvre (course rate, surge, heave) changes at random, seeded times.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from scenarios.config.base import NonNegFloat, PositiveFloat, Probability, StrictModel, Vec2, Vec3


class BubbleConfig(StrictModel):
    """Regulator exhaust: a cluster of small strong scatterers released at the regulator every
    breath (every ``breath_period_s``, each interval jittered), rising (rise speed of 2-6 mm
    bubbles: 0.2-0.3 m/s, docs/references.md [BubbleRise]) and spreading horizontally (each
    scatterer keeps a horizontal spread velocity, so the cluster's radius grows linearly
    with its age), carried by the water current and, for a moment, by the diver's wake
    (a ``wake_fraction`` of the diver's speed through the water, decaying with
    ``wake_decay_s``); they stay where released while the diver swims on."""

    enabled: bool = True
    breath_period_s: PositiveFloat = Field(4.5, ge=1.0, le=30.0, description="mean time between breaths, s")
    breath_jitter_s: NonNegFloat = Field(0.5, le=10.0, description="sigma of each breath interval, s "
                                         "(intervals clipped to 0.6-1.4 x breath_period_s)")
    per_breath: int = Field(5, ge=1, le=20)
    rise_speed_mps: PositiveFloat = Field(0.25, le=1.0)
    rise_speed_sigma_mps: NonNegFloat = Field(0.03, le=0.5)
    dispersion_mps: NonNegFloat = Field(0.06, le=1.0, description="horizontal spread speed sigma, m/s "
                                        "(a spreading half-angle of atan(0.06 / 0.25) = 13 deg)")
    wake_fraction: NonNegFloat = Field(0.3, le=1.0, description="share of the diver's speed through the "
                                       "water given to a breath at release (estimate)")
    wake_decay_s: PositiveFloat = Field(1.5, le=30.0, description="time constant of the wake's push, s (estimate)")
    radius_m: PositiveFloat = Field(0.06, le=0.5, description="scatterer size (a bubble group)")
    lifetime_s: PositiveFloat = Field(10.0, le=120.0)
    reflectivity: Probability = 1.0
    release_offset_body_m: Vec3 = Field((0.8, 0.0, -0.25), description="regulator, FRD from the centre")


class MoverConfig(StrictModel):
    """A moving target on a mocap body.

    ``kind``: ``diver`` (a 1.8 m x 0.4 m capsule, prone, swimming along its course) or
    ``vehicle`` (a 0.7 x 0.7 x 0.35 m box, PlaDyPos-sized, paper 004 section 5). Motion:
    surge speed, course rate and heave speed are held for exponential times of mean
    ``manoeuvre_mean_s`` and redrawn (surge ~ N(surge_mps, surge_sigma_mps) clipped at 0,
    course rate ~ N(0, course_rate_sigma_dps), heave ~ N(0, heave_sigma_mps)); depth stays in
    ``depth_band_m`` and, outside ``leash_radius_m`` of ``leash_center_ne_m``, the next
    manoeuvre heads back to the centre.
    """

    name: str = Field(min_length=1)
    kind: Literal["diver", "vehicle"] = "diver"
    initial_pos_ned: Vec3
    initial_course_deg: float = Field(0.0, ge=-360.0, le=360.0)
    surge_mps: NonNegFloat = Field(0.3, le=3.0)
    surge_sigma_mps: NonNegFloat = Field(0.1, le=3.0)
    course_rate_sigma_dps: NonNegFloat = Field(6.0, le=90.0)
    heave_sigma_mps: NonNegFloat = Field(0.03, le=1.0)
    manoeuvre_mean_s: PositiveFloat = Field(8.0, ge=0.5, le=600.0)
    depth_band_m: tuple[NonNegFloat, NonNegFloat] = (1.0, 10.0)
    leash_center_ne_m: Vec2 | None = Field(None, description="default: the initial position")
    leash_radius_m: PositiveFloat = Field(15.0, le=1000.0)
    reflectivity: Probability = 0.5
    class_name: str = "diver"
    bubbles: BubbleConfig = BubbleConfig(enabled=False)

    @model_validator(mode="after")
    def _band(self) -> "MoverConfig":
        lo, hi = self.depth_band_m
        if not lo <= self.initial_pos_ned[2] <= hi:
            raise ValueError(f"initial depth {self.initial_pos_ned[2]} m outside depth_band_m {self.depth_band_m}")
        return self
