"""Target geolocalisation and PMHA world-model configs."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from scenarios.config.base import NonNegFloat, PositiveFloat, Probability, StrictModel


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
        0.15, description="isotropic floor added to the covariance: where on an object the ATR box lands"
        " varies with aspect, an error correlated across frames that the per-frame terms miss",
    )


class WorldModelConfig(StrictModel):
    """Probabilistic multiple hypothesis anchoring (paper 000 section V; docs/references.md [P000]).

    Each measurement of a scan is a new object, an existing anchor or clutter. The origin
    priors are the anchoring authors' defaults; with Poisson new/clutter counts they are
    Reid's rates relative to a detection (expected new = p_new / p_existing per scan).
    Densities are used when the PMHA is built without a surveyed region (otherwise 1/volume).
    """

    p_new: Probability = Field(0.14, description="prior that a measurement is a new object")
    p_existing: Probability = Field(0.14, description="prior that it comes from an anchor")
    p_clutter: Probability = Field(0.72, description="prior that it is a false detection")
    new_density_per_m3: PositiveFloat = Field(1e-4, description="uniform density of new objects")
    clutter_density_per_m3: PositiveFloat = Field(1e-4, description="uniform clutter density")
    p_detect: Probability = Field(0.9, description="detection probability of a visible anchor")
    visibility_floor: Probability = Field(
        0.05, description="least visibility probability, so anchors just outside the fan can "
        "still be associated (and are barely penalised for not being seen)"
    )
    max_hypotheses: int = Field(100, ge=1, le=100_000)
    prune_ratio: float = Field(1e-10, gt=0.0, lt=1.0, description="drop below ratio x best")
    gate_mahalanobis2: PositiveFloat = Field(
        25.0, description="squared Mahalanobis gate for anchor associations"
    )
    process_noise_m2_per_s: NonNegFloat = Field(
        1e-3, description="constant-position KF process noise (static objects)"
    )
    kf_timeout_s: PositiveFloat = Field(
        60.0, description="after this long unmeasured, position falls back to a fixed Gaussian"
    )
    fallback_cov_m2: PositiveFloat = Field(1.0, description="fixed Gaussian variance per axis")
    measurement_cov_m2: PositiveFloat | None = Field(
        None, description="if set, replaces each measurement covariance by this x I3 (paper: 1)"
    )
    use_class_likelihood: bool = Field(True, description="class pmf enters the association")
    class_score_floor: float = Field(0.01, gt=0.0, lt=0.5, description="ATR score clip")
    min_detections: int = Field(2, ge=1, description="supporting detections to report an object")
    region_margin_m: float = Field(
        10.0, ge=0.0, le=1000.0,
        description="surveyed region = survey waypoints' bounding box grown by this (m); no new objects outside",
    )
    drop_tentative_after_s: PositiveFloat | None = Field(
        60.0, description="forget anchors below min_detections unmeasured this long"
    )

    @model_validator(mode="after")
    def _priors_sum_to_one(self) -> "WorldModelConfig":
        total = self.p_new + self.p_existing + self.p_clutter
        if abs(total - 1.0) > 1e-6:
            raise ValueError(
                f"autonomy.world_model: p_new + p_existing + p_clutter must be 1, got {total:.6g}"
            )
        if min(self.p_new, self.p_existing, self.p_clutter) <= 0.0:
            raise ValueError("autonomy.world_model: p_new, p_existing, p_clutter must be > 0")
        return self
