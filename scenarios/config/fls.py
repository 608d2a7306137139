"""Forward-looking sonar config.

``preset`` picks the hardware (docs/references.md [BlueViewM900], [ARIS3000]); every geometry field left at ``None``
takes the preset's value, so a scenario overrides only what it changes. The fields tuned to a
preset are :data:`PRESET_KEYS`: a ``--set`` that changes an entry's ``preset`` resets the ones
the scenario file set to the new preset's values, unless the same command line sets them too
(:func:`scenarios.load.load_scenario`). Levels are in dB; intensities are linear power.
Acoustic constants marked "estimate" are ours, not datasheet.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from scenarios.config.sensor import SensorConfig, sensor_config
from scenarios.config.sonar_formation import SonarFormationConfig

FlsPresetName = Literal["m900_130", "aris3000", "aris3000_lf"]

#: Geometry fields whose ``None`` means the preset's value (the hardware's own figures).
PRESET_GEOMETRY_KEYS = ("fov_deg", "n_beams", "vertical_beamwidth_deg", "range_min_m", "range_max_m",
                        "range_resolution_m", "beamwidth_az_deg", "absorption_db_per_m", "fan_size_px",
                        "range_window_m")
#: Fields a scenario tunes to its preset: the geometry and the ray columns across the beams
#: (``azimuth_columns`` may not exceed the preset's ``n_beams``).
PRESET_KEYS = PRESET_GEOMETRY_KEYS + ("azimuth_columns",)


@sensor_config
class FlsConfig(SensorConfig):
    """Forward-looking sonar: geometry, ray sampling, image formation and output.

    Geometry (``None`` = preset value): ``fov_deg`` horizontal field of view, ``n_beams``
    output beams, ``vertical_beamwidth_deg`` elevation aperture, ``range_min_m`` /
    ``range_max_m`` hardware limits, ``range_window_m`` the displayed (near, far) window
    inside them, ``range_resolution_m`` the polar bin size, ``beamwidth_az_deg`` the -3 dB
    one-way horizontal beam width, ``absorption_db_per_m`` one-way absorption,
    ``fan_size_px`` the (width, height) of the Cartesian fan image.

    Mount: the head sits at hull site ``mount_site`` (default ``fls``, whatever the entry's
    name) or at ``mount_pos_body_m``; its boresight is pitched down by ``tilt_deg``, and
    ``mount_rpy_deg`` gives its roll and yaw (its pitch must stay 0: use ``tilt_deg``).
    """

    kind: Literal["fls"] = "fls"

    preset: FlsPresetName = "m900_130"
    rate_hz: float = Field(3.0, gt=0.0, le=100.0)
    latency_s: float = Field(0.05, ge=0.0, le=5.0, description="sampling to delivery, s")
    mount_site: str | None = Field("fls", min_length=1, description="hull site the head sits at")
    tilt_deg: float = Field(10.0, ge=-45.0, le=90.0, description="boresight pitch down")

    fov_deg: float | None = Field(None, gt=0.0, le=180.0)
    n_beams: int | None = Field(None, ge=2, le=4096)
    vertical_beamwidth_deg: float | None = Field(None, gt=0.0, le=90.0)
    range_min_m: float | None = Field(None, ge=0.0, le=1000.0)
    range_max_m: float | None = Field(None, gt=0.0, le=1000.0)
    range_window_m: tuple[float, float] | None = Field(
        None, description="displayed (near, far) range, m; default = hardware limits")
    range_resolution_m: float | None = Field(None, gt=0.0, le=1.0)
    beamwidth_az_deg: float | None = Field(None, gt=0.0, le=20.0)
    absorption_db_per_m: float | None = Field(None, ge=0.0, le=10.0)
    fan_size_px: tuple[int, int] | None = Field(None, description="fan image (width, height)")

    # Ray sampling
    elevation_rays: int = Field(
        16, ge=2, le=512, description="rays per azimuth column across the vertical beam")
    azimuth_columns: int | None = Field(
        None, ge=2, le=4096, description="ray columns across the FOV (None = one per beam); "
        "fewer columns are interpolated to the beams")
    edge_refine_iters: int = Field(
        6, ge=0, le=20, description="bisection steps locating silhouette / shadow edges")

    # Image formation
    scattering_exponent: float = Field(1.0, ge=0.0, le=10.0, description="m in cos^m(incidence)")
    side_lobe_extent_beamwidths: float = Field(
        3.0, ge=0.0, le=20.0, description="azimuth beam-pattern kernel half-width")
    speckle: Literal["none", "rayleigh", "k"] = Field(
        "rayleigh", description="rayleigh: exponential intensity; k: K-distributed seabed clutter")
    speckle_generator: Literal["counter", "stream"] = Field(
        "counter", description="counter: one draw per frame keys a hash per pixel, the speckle (rayleigh or "
        "k) and the dB display in one pass (used without the formation model's correlated speckle, texture, "
        "Rice objects or power-law display; otherwise stream); stream: every pixel drawn from the sensor's "
        "generator (the renderer before)")
    k_shape: float = Field(2.0, gt=0.0, le=100.0, description="K-distribution shape (texture)")
    noise_floor_db: float = Field(
        -90.0, ge=-200.0, le=0.0, description="receiver noise power before TVG, dB re one base "
        "ray's return from a unit-reflectivity surface at normal incidence and 1 m")
    tvg_spreading_db_per_decade: float = Field(
        20.0, ge=0.0, le=60.0, description="time-varied gain, N log10(r)")
    tvg_absorption: bool = Field(True, description="TVG also compensates 2 alpha r")
    gain_db: float = Field(0.0, ge=-100.0, le=200.0, description="added after TVG; 0 dB shows as 255")
    dynamic_range_db: float = Field(50.0, gt=1.0, le=150.0, description="dB below 0 mapped to 0..255")
    formation: SonarFormationConfig = Field(
        SonarFormationConfig(), description="correlated speckle, seabed texture, reverberation, display law")

    # Ground truth
    min_visible_fraction: float = Field(
        0.2, ge=0.0, le=1.0, description="visible flag threshold on the visible fraction")

    @model_validator(mode="after")
    def _check_window(self) -> "FlsConfig":
        if self.mount_rpy_deg[1] != 0.0:
            raise ValueError("mount_rpy_deg pitch must be 0 for a sonar: set its tilt with tilt_deg")
        w = self.range_window_m
        if w is not None and not (0.0 <= w[0] < w[1]):
            raise ValueError(f"range_window_m must be (near, far) with 0 <= near < far, got {w}")
        if self.range_min_m is not None and self.range_max_m is not None and not (
                self.range_min_m < self.range_max_m):
            raise ValueError("range_min_m must be < range_max_m")
        if self.fan_size_px is not None and min(self.fan_size_px) < 16:
            raise ValueError(f"fan_size_px must be at least 16 x 16, got {self.fan_size_px}")
        return self
