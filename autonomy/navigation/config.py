"""Navigation filter config.

The filter's model of its sensors' noise is :class:`autonomy.navigation.NavNoiseModel`
(the simulator fills it from its sensor configs); this block holds only what belongs to the
filter itself.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from autonomy.config_base import StrictModel


class SpeedModelConfig(StrictModel):
    """The vehicle's own surge/sway speed model, driven by the autopilot's commanded force
    (DVL-free dead reckoning, :class:`autonomy.navigation.speed_model.SpeedModel`): per axis
    ``m dv/dt = F - d_lin v - d_quad v |v|``; heave is modelled as 0 with a fast random walk, so
    the depth sensor gives the vertical velocity. Values are the onboard estimate of the hull (for a
    BlueROV2 Heavy: von Benzon et al. 2022, mass + added mass, linear and quadratic damping)."""

    mass_kg: tuple[float, float] = Field(..., description="surge, sway: rigid-body + added mass, kg")
    damping_linear: tuple[float, float] = Field(..., description="surge, sway, N s/m")
    damping_quadratic: tuple[float, float] = Field(..., description="surge, sway, N s^2/m^2")
    noise_mps_per_sqrt_s: float = Field(0.01, ge=0.0, le=10.0, description="surge/sway model error random walk")
    heave_noise_mps_per_sqrt_s: float = Field(
        0.2, ge=0.0, le=10.0, description="heave (modelled as 0) error random walk: the depth sensor sets it")
    scale_sigma: float = Field(0.2, ge=0.0, le=10.0, description="prior sigma of the model's speed scale error")

    @model_validator(mode="after")
    def _positive(self) -> "SpeedModelConfig":
        if min(self.mass_kg) <= 0.0 or min(self.damping_linear) < 0.0 or min(self.damping_quadratic) < 0.0:
            raise ValueError("speed_model: mass_kg must be > 0 and damping_linear, damping_quadratic >= 0")
        if min(self.damping_linear) + min(self.damping_quadratic) <= 0.0:
            raise ValueError("speed_model: each axis needs some damping (linear or quadratic > 0)")
        return self


class NavigationConfig(StrictModel):
    """``mode='ekf'`` fuses GPS (and USBL) position fixes; ``'dead_reckoning'`` ignores them
    (AHRS + DVL + depth only).

    ``velocity_source``: ``dvl`` (bottom-track velocity) or ``speed_model`` (no DVL: the
    :class:`SpeedModelConfig` model driven by the commanded force, its error a random walk the
    position fixes estimate); ``speed_model`` needs the ``speed_model`` block."""

    mode: Literal["ekf", "dead_reckoning"] = "ekf"
    velocity_source: Literal["dvl", "speed_model"] = "dvl"
    speed_model: SpeedModelConfig | None = None
    initial_pos_sigma_m: float = Field(1.0, ge=0.0, le=1000.0, description="north/east prior")
    initial_depth_sigma_m: float = Field(0.1, ge=0.0, le=100.0)
    initial_vel_sigma_mps: float = Field(0.05, ge=0.0, le=10.0, description="before first DVL")
    hold_accel_sigma_mps2: float = Field(
        0.03, ge=0.0, le=10.0, description="unmodelled acceleration while a DVL ping is held"
    )
    dvl_lost_noise_mps_per_sqrt_s: float = Field(
        0.05, ge=0.0, le=10.0, description="extra velocity random walk once bottom lock is lost"
    )
    dvl_timeout_s: float = Field(1.0, gt=0.0, le=60.0, description="age at which lock counts as lost")
    gps_gate_chi2: float | None = Field(
        13.8, gt=0.0, description="innovation gate (2 dof); 13.8 = 99.9 %; None disables"
    )
    usbl_range_noise_m: float = Field(0.1, ge=0.0, le=100.0)
    usbl_range_noise_frac: float = Field(0.005, ge=0.0, le=1.0)
    usbl_angle_noise_deg: float = Field(0.5, ge=0.0, le=45.0)
    usbl_gate_chi2: float | None = Field(16.3, gt=0.0, description="3 dof; 16.3 = 99.9 %")

    @model_validator(mode="after")
    def _speed_model_given(self) -> "NavigationConfig":
        if self.velocity_source == "speed_model" and self.speed_model is None:
            raise ValueError("velocity_source 'speed_model' needs the speed_model block (mass_kg, damping_linear, "
                             "damping_quadratic)")
        return self
