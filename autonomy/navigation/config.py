"""Navigation filter config.

The filter's model of its sensors' noise is :class:`autonomy.navigation.NavNoiseModel`
(the simulator fills it from its sensor configs); this block holds only what belongs to the
filter itself.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from autonomy.config_base import StrictModel


class NavigationConfig(StrictModel):
    """``mode='ekf'`` fuses GPS (and USBL) position fixes; ``'dead_reckoning'`` ignores them
    (AHRS + DVL + depth only)."""

    mode: Literal["ekf", "dead_reckoning"] = "ekf"
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
