"""Target geolocalisation config."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from autonomy.config_base import NonNegFloat, PositiveFloat, StrictModel


class LocalizationConfig(StrictModel):
    """Detection (range, azimuth) -> NED position and covariance (paper 000, eqs. 4-6).

    ``flat_seabed`` solves the elevation angle from the altitude assuming a locally flat
    seabed (eqs. 5-6, generalised to any azimuth and vehicle attitude); ``planar`` sets the
    elevation to zero (eq. 4). Standard deviations are one-sigma and are propagated to
    first order, together with the navigation covariance, into the NED covariance.
    """

    method: Literal["flat_seabed", "planar"] = "flat_seabed"
    range_sigma_m: PositiveFloat = Field(0.05, description="range noise of the reference point")
    azimuth_sigma_rad: PositiveFloat = Field(0.0087, description="azimuth noise (~0.5 deg)")
    altitude_sigma_m: NonNegFloat = Field(0.1, description="altimeter noise (flat_seabed only)")
    attitude_sigma_rad: NonNegFloat = Field(
        0.005, description="roll/pitch uncertainty of the navigation solution"
    )
    tilt_sigma_rad: NonNegFloat = Field(0.0, description="uncertainty of the sonar mount tilt")
    box_sigma_fraction: NonNegFloat = Field(
        0.2, le=1.0, description="extra sigma as a fraction of the box's range/azimuth extent"
    )
    range_offset_m: float = Field(
        0.0, ge=-5.0, le=5.0, description="added to the detection range (leading edge -> centre)"
    )
    min_sigma_m: NonNegFloat = Field(
        0.07, description="sigma per axis of where on an object the ATR box lands (m): varies with aspect "
        "but is common to the looks at one object, so it is a shared error (LocalizedDetection.shared_ned) "
        "that repeated looks do not average out; chosen so that the world model's mean NEES with the true "
        "pose is 2 on cssn_lawnmower seeds 0-4 (0.08 m gave 1.50, 0.15 m 0.54; NEES scales as 1 / sigma^2)",
    )
