"""Target tracker config (paper 004): which measurements, the filter's noise model, gates, ROI."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from autonomy.config_base import StrictModel


class TrackingConfig(StrictModel):
    """``mode``: ``sonar`` (sonar detections only), ``usbl`` (USBL fixes only) or ``fused``
    (both), the three configurations of paper 004 section 5. Noise terms are 1 sigma; the
    process noise is a white-noise intensity per second on course rate, surge and heave
    (paper 004 eq. 6); until the course is known (its 1 sigma below
    ``initiation_course_sigma_deg``) the filter runs a Cartesian constant-velocity model
    (``initiation_accel_noise_m2_per_s3``), whose Gaussian velocity prior is consistent where a
    course drawn uniformly on the circle is not; ``roi_sigma`` scales the polar ROI half-widths (paper 004 eq. 16).

    Sonar noise: ``sonar_range_sigma_m`` and ``sonar_azimuth_sigma_deg`` are the white part
    (the image's resolution); the target's extent adds a part that is correlated from frame
    to frame (which part of the body the echo shows): ``target_thickness_m / sqrt(12)`` along
    the beam and ``target_size_m / sqrt(12)`` across it (a uniform over the extent), with the
    correlation time ``sonar_error_correlation_s`` (see :meth:`TargetTracker.on_sonar`)."""

    enabled: bool = False
    mode: Literal["sonar", "usbl", "fused"] = "fused"
    transponder: str = Field("diver", min_length=1, description="transponder the USBL fixes must name")
    usbl_sensor: str = Field("usbl", min_length=1)
    sonar_sensor: str = Field("fls", min_length=1)
    rate_hz: float = Field(10.0, gt=0.0, le=100.0, description="filter output rate (paper: 10 Hz)")
    pos_noise_m2_per_s: float = Field(0.002, ge=0.0, le=10.0)
    course_rate_noise_rad2_per_s3: float = Field(0.002, ge=0.0, le=10.0)
    surge_noise_m2_per_s3: float = Field(0.005, ge=0.0, le=10.0)
    heave_noise_m2_per_s3: float = Field(0.001, ge=0.0, le=10.0)
    initial_surge_mps: float = Field(0.2, ge=0.0, le=5.0)
    initial_surge_sigma_mps: float = Field(0.3, gt=0.0, le=5.0)
    initial_course_rate_sigma_dps: float = Field(5.0, gt=0.0, le=180.0)
    initiation_accel_noise_m2_per_s3: float = Field(
        0.006, ge=0.0, le=10.0,
        description="white-noise acceleration of the constant-velocity start: about the surge noise plus the "
                    "cross-track u^2 q_r t of a 0.2 m/s course-rate walk over 10 s")
    initiation_course_sigma_deg: float = Field(
        20.0, gt=0.0, le=90.0, description="course 1-sigma below which the start hands over to eq. 6")
    usbl_range_sigma_m: float = Field(0.1, gt=0.0, le=50.0)
    usbl_range_sigma_frac: float = Field(0.01, ge=0.0, le=0.5)
    usbl_angle_sigma_deg: float = Field(1.0, gt=0.0, le=45.0)
    usbl_angle_sigma_deg_per_100m: float = Field(1.0, ge=0.0, le=45.0)
    sonar_range_sigma_m: float = Field(0.1, gt=0.0, le=10.0)
    sonar_azimuth_sigma_deg: float = Field(0.5, gt=0.0, le=20.0)
    sonar_vertical_beam_deg: float = Field(14.0, gt=0.0, le=90.0, description="elevation within the beam")
    target_thickness_m: float = Field(
        0.4, ge=0.0, le=10.0, description="the target's extent along the sonar beam (a diver: 0.4 m across): its echo "
        "comes from the side facing the sonar, so a detection's range is taken as half of it short of the centre")
    sonar_error_correlation_s: float = Field(
        10.0, ge=0.0, le=600.0, description="correlation time of a detection's centre error from the target's extent "
        "(which part of the body the echo shows changes as the target turns: about its manoeuvre time); 0: white")
    gate_probability: float = Field(0.999, gt=0.0, lt=1.0, description="chi-square gate on each update")
    usbl_rejections_to_restart: int = Field(3, ge=1, le=100, description="USBL fixes gated out in a row: restart")
    roi_sigma: float = Field(2.45, gt=0.0, le=10.0, description="ROI half-width in sigmas (2.45: 95 % in 2-D)")
    target_size_m: float = Field(1.0, ge=0.0, le=10.0, description="target extent added to the ROI")
    history_s: float = Field(10.0, gt=0.0, le=120.0, description="how late a fix may be re-processed")
    detector_score_threshold: float = Field(0.2, ge=0.0, le=1.0)
    min_extent_frac: float = Field(
        0.8, ge=0.0, le=2.0, description="smallest cluster extent taken for the target, x target_size_m "
        "(a diver seen end-on still smears over ~0.8 m; a breath's bubble cluster rarely does)")
    min_area_frac: float = Field(
        0.25, ge=0.0, le=4.0, description="smallest foreground area taken for the target, x target_size_m^2")
