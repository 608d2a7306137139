"""Side-scan sonar config (``kind: sss``).

Two transducers, port and starboard, each a narrow along-track beam and a wide vertical
aperture depressed below the horizontal. The ping rate follows from the range: a ping waits
for the two-way travel time to ``range_max_m`` (``rate_hz = sound_speed / (2 range_max)``).
Acoustic constants are of a 400-kHz-class towed/hull-mounted side-scan (estimates, not a
datasheet).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from scenarios.config.base import Vec3
from scenarios.config.sensor import SensorConfig, sensor_config
from scenarios.config.sonar_formation import SonarFormationConfig


@sensor_config
class SssConfig(SensorConfig):
    """Side-scan sonar: geometry, ray sampling, echo chain and output.

    Geometry: ``range_max_m`` slant range per side, ``n_bins`` slant-range bins per side
    (bin k spans ``[k, k + 1) * range_max_m / n_bins``), ``depression_deg`` the boresight
    below the horizontal, ``vertical_beamwidth_deg`` the one-way -3 dB vertical width,
    ``along_track_beamwidth_deg`` the one-way -3 dB along-track width. The rays of a side
    span from ``vertical_beamwidth_deg`` above the boresight down to the vertical (so the
    first bottom return is at the altitude and the nadir gap is the water column).
    ``rate_hz`` left out is the two-way travel-time limit ``sound_speed_mps / (2 range_max_m)``.
    ``ground_range``: also resample each line to ground range with the altitude of the first
    bottom return (flat-seabed correction).
    """

    kind: Literal["sss"] = "sss"
    rate_hz: float = Field(None, gt=0.0, le=200.0, description="left out: sound_speed / (2 range_max)")
    latency_s: float = Field(0.0, ge=0.0, le=5.0)
    mount_pos_body_m: Vec3 | None = Field((0.0, 0.0, 0.2), description="FRD offset of both transducers, m")

    range_max_m: float = Field(75.0, gt=1.0, le=1000.0)
    n_bins: int = Field(1000, ge=16, le=8192)
    sound_speed_mps: float = Field(1500.0, ge=1400.0, le=1600.0)
    depression_deg: float = Field(20.0, ge=0.0, le=60.0)
    vertical_beamwidth_deg: float = Field(50.0, gt=1.0, le=120.0)
    along_track_beamwidth_deg: float = Field(0.8, gt=0.05, le=10.0)
    absorption_db_per_m: float = Field(0.1, ge=0.0, le=10.0, description="one-way, dB/m (estimate, ~400 kHz)")

    elevation_rays: int = Field(48, ge=4, le=1024, description="rays per side across the vertical span")
    along_track_rays: int = Field(1, ge=1, le=15, description="ray columns across the along-track beam")
    edge_refine_iters: int = Field(6, ge=0, le=20)

    scattering_exponent: float = Field(2.0, ge=0.0, le=10.0, description="m in cos^m(incidence); 2 = Lambert")
    speckle: Literal["none", "rayleigh", "k"] = "rayleigh"
    k_shape: float = Field(2.0, gt=0.0, le=100.0)
    noise_floor_db: float = Field(-110.0, ge=-200.0, le=0.0)
    tvg_spreading_db_per_decade: float = Field(30.0, ge=0.0, le=60.0, description="30: area scattering")
    tvg_absorption: bool = True
    gain_db: float = Field(-25.0, ge=-100.0, le=200.0)
    dynamic_range_db: float = Field(50.0, gt=1.0, le=150.0)
    ground_range: bool = Field(False, description="also output ground-range lines")
    formation: SonarFormationConfig = Field(
        SonarFormationConfig(), description="correlated speckle along range, seabed texture, reverberation, "
        "display law (the forward-looking sonar's beam, elevation and object-tail fields do not apply)")

    @model_validator(mode="before")
    @classmethod
    def _ping_rate(cls, data):
        if isinstance(data, dict) and data.get("rate_hz") is None:
            c = data.get("sound_speed_mps", cls.model_fields["sound_speed_mps"].default)
            r = data.get("range_max_m", cls.model_fields["range_max_m"].default)
            try:
                data = {**data, "rate_hz": float(c) / (2.0 * float(r))}
            except (TypeError, ValueError, ZeroDivisionError):
                pass  # the field validators report the bad value
        return data

    @model_validator(mode="after")
    def _check(self) -> "SssConfig":
        f = self.formation
        fls_only = {"beam_correlated_speckle": f.beam_correlated_speckle,
                    "elevation_span_beamwidths": f.elevation_span_beamwidths != 1.0,
                    "object_tail_m": f.object_tail_m is not None, "object_tail_ratio": f.object_tail_ratio != 0.0,
                    "object_rice_k": f.object_rice_k != 0.0, "side_lobe_floor_db": f.side_lobe_floor_db is not None,
                    "object_back_wall_ratio": f.object_back_wall_ratio != 0.0,
                    "object_specular_share": f.object_specular_share != 0.0,
                    "object_back_wall_repeats": f.object_back_wall_repeats != 1}
        set_here = [k for k, v in fls_only.items() if v]
        if set_here:
            raise ValueError(f"formation.{set_here[0]}: a forward-looking sonar field (so are "
                             f"{', '.join(k for k in fls_only if k != set_here[0])}); a side-scan takes "
                             "pulse_length_m, texture_*, reverberation_db and display_*")
        limit = self.sound_speed_mps / (2.0 * self.range_max_m)
        if self.rate_hz > limit * (1.0 + 1e-9):
            raise ValueError(f"rate_hz {self.rate_hz} exceeds the two-way travel-time limit "
                             f"sound_speed_mps / (2 range_max_m) = {limit:.4g} Hz")
        if any(self.mount_rpy_deg):
            raise ValueError("mount_rpy_deg must be (0, 0, 0) for a side-scan sonar: the sides look at +-90 deg "
                             "and the depression is depression_deg")
        return self
