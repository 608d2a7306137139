"""PMHA world-model config."""

from __future__ import annotations

from pydantic import Field, model_validator

from autonomy.config_base import NonNegFloat, PositiveFloat, Probability, StrictModel


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
    consider_shared_errors: bool = Field(
        True, description="keep the errors detections share (navigation position and heading, where on "
        "the object the box lands) from averaging out over repeated looks (Schmidt consider update); "
        "false: every detection's error is independent (paper 000's model), so ellipses shrink below "
        "the navigation error",
    )
    class_score_floor: float = Field(0.01, gt=0.0, lt=0.5, description="ATR score clip")
    min_detections: int = Field(2, ge=1, description="supporting detections to report an object")
    region_margin_m: float = Field(
        10.0, ge=0.0, le=1000.0,
        description="surveyed region = survey waypoints' bounding box grown by this (m); no new objects outside",
    )
    drop_tentative_after_s: PositiveFloat | None = Field(
        60.0, description="forget anchors below min_detections unmeasured this long"
    )
    scan_cluster_mahalanobis2: PositiveFloat | None = Field(
        16.3, description="detections of one scan whose difference passes this squared Mahalanobis "
        "gate are one object's (duplicate boxes) and enter as one measurement; None: each detection "
        "is a separate point measurement; 16.3 = 99.9 % of one point's pairs (3 dof)",
    )
    merge_mahalanobis2: PositiveFloat | None = Field(
        1.0, description="once the hypothesis budget is full, versions of one anchor with the same "
        "detection count this close (squared Mahalanobis distance, summed covariances) count as one, "
        "so hypotheses differing only in them merge; None: no merging (budget keeps the top worlds)",
    )
    duplicate_mahalanobis2: PositiveFloat | None = Field(
        11.34, description="objects of the world model whose track-to-track squared Mahalanobis distance "
        "(their shared errors cancelled) passes this gate and whose centres are within "
        "duplicate_max_separation_m are reported as one object, fused (Bar-Shalom-Campo), and an object's "
        "existence counts the worlds holding any anchor that passes it with the object; 11.34 = 99 % of "
        "one object's pairs (3 dof); None: never (existence: the symbol's own worlds)",
    )
    duplicate_max_separation_m: PositiveFloat = Field(
        0.5, description="objects closer than this are one echo to a forward-looking sonar's detector, "
        "so the duplicate test may join them; farther ones are always two",
    )
    max_per_world: int = Field(
        10, ge=1, le=100_000,
        description="once the budget is full, hypotheses kept per distinct set of objects; a further "
        "child with the same objects adds its probability to that world's best hypothesis",
    )
    max_expanded_children: int = Field(
        2000, ge=1, le=10_000_000,
        description="children drawn per scan at most once the budget is full (bounds update time)",
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
