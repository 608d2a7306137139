"""Settings of the surface vessel's autonomy (:mod:`autonomy.surface.buoy`).

Speeds in m/s, gains per second, angles in degrees in the config.
"""

from __future__ import annotations

from pydantic import Field

from autonomy.config_base import PositiveFloat, StrictModel


class SurfaceNavigationConfig(StrictModel):
    """Constant-velocity Kalman filter on GNSS fixes (north, east)."""

    gnss_noise_m: PositiveFloat = Field(0.7, le=50.0, description="assumed fix noise per horizontal axis")
    accel_noise_mps2: PositiveFloat = Field(0.03, le=5.0, description="white acceleration of the CV model")
    max_fix_gap_s: PositiveFloat = Field(10.0, le=600.0, description="no fix for longer: estimate invalid")


class SurfaceAutonomyConfig(StrictModel):
    """Guidance and control of a 3-DOF surface vessel.

    The position loop asks for a velocity ``v_d = clip(k_pos * e, max_speed)`` (plus the
    followed point's velocity), the velocity loop is a PI on the mass-scaled velocity error
    in NED plus a surge-drag feedforward (its integral takes up the current's drag), and the
    heading follows the low-passed demanded force (the surge thrusters are the strongest): on
    the move the bow points along the track, in a hold it weathervanes into the current.
    """

    rate_hz: float = Field(10.0, gt=0.0, le=100.0)
    max_speed_mps: PositiveFloat = Field(0.55, le=5.0, description="ground-speed demand limit")
    k_pos_per_s: PositiveFloat = Field(0.15, le=5.0, description="position error -> velocity demand")
    k_vel_per_s: PositiveFloat = Field(0.8, le=20.0, description="velocity error -> acceleration demand")
    ki_vel_per_s2: float = Field(0.08, ge=0.0, le=10.0, description="integral of the velocity error")
    integral_limit_mps2: PositiveFloat = Field(0.3, le=10.0, description="max |integral acceleration|")
    drag_linear_n_per_mps: float = Field(8.0, ge=0.0, le=1e4, description="surge drag model, feedforward")
    drag_quadratic_n_per_mps2: float = Field(27.7, ge=0.0, le=1e4, description="surge drag model, feedforward")
    force_filter_tau_s: PositiveFloat = Field(4.0, le=120.0, description="smoothing of the force the heading follows")
    mass_kg: PositiveFloat = Field(40.0, le=10000.0, description="mass + surge added mass used to scale forces")
    yaw_inertia_kgm2: PositiveFloat = Field(9.1, le=10000.0, description="I_z + N_rdot")
    yaw_bandwidth_radps: PositiveFloat = Field(0.8, le=20.0)
    yaw_damping_ratio: PositiveFloat = Field(1.0, le=5.0)
    min_heading_force_n: PositiveFloat = Field(1.0, le=1e4, description="below it the heading setpoint is kept")
    target_filter_tau_s: PositiveFloat = Field(3.0, le=120.0, description="smoothing of the followed point's velocity")
    navigation: SurfaceNavigationConfig = SurfaceNavigationConfig()
