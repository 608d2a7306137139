"""Settings of the surface vessel's autonomy (:mod:`autonomy.surface.buoy`).

Speeds in m/s, gains per second, angles in degrees in the config.
"""

from __future__ import annotations

from pydantic import Field

from autonomy.config_base import NonNegFloat, PositiveFloat, StrictModel


class SurfaceNavigationConfig(StrictModel):
    """Kalman filter on GNSS fixes with the thrust as input and a disturbance state
    (:mod:`autonomy.surface.navigation`)."""

    gnss_noise_m: PositiveFloat = Field(0.7, le=50.0, description="assumed fix noise per horizontal axis")
    accel_noise_mps2: PositiveFloat = Field(0.02, le=5.0, description="white acceleration the model misses")
    disturbance_walk_mps2: PositiveFloat = Field(0.002, le=5.0, description="random walk of the disturbance, per sqrt(s)")
    initial_disturbance_mps2: PositiveFloat = Field(0.1, le=10.0, description="its standard deviation at the first fix")
    max_fix_gap_s: PositiveFloat = Field(10.0, le=600.0, description="no fix for longer: estimate invalid")


class SurfaceAutonomyConfig(StrictModel):
    """Guidance and control of a 3-DOF surface vessel.

    The position loop asks for a velocity ``v_d = clip(k_pos * e, max_speed)`` (plus the
    followed point's velocity), the velocity loop is a P on the mass-scaled velocity error in
    NED plus an integral of the position error (it takes up the current's drag; integrating
    the velocity error instead would feed the GNSS position noise straight into it) plus a
    surge-drag feedforward, and the
    heading follows the low-passed steady part of the force, drag feedforward + integral,
    not the noisy proportional part (the surge thrusters are the strongest): on
    the move the bow points along the track, in a hold it weathervanes into the current.
    """

    rate_hz: float = Field(10.0, gt=0.0, le=100.0)
    max_speed_mps: PositiveFloat = Field(0.6, le=5.0, description="ground-speed demand limit")
    k_pos_per_s: PositiveFloat = Field(0.15, le=5.0, description="position error -> velocity demand")
    k_vel_per_s: PositiveFloat = Field(0.8, le=20.0, description="velocity error -> acceleration demand")
    ki_pos_per_s3: float = Field(0.01, ge=0.0, le=10.0, description="integral of the position error -> acceleration")
    integral_limit_mps2: PositiveFloat = Field(0.1, le=10.0, description="max |integral acceleration|")
    model_mass_kg: tuple[PositiveFloat, PositiveFloat] = Field(
        (40.0, 59.7), description="surge, sway mass + added mass (filter input, force scaling)")
    model_drag_linear_n_per_mps: tuple[NonNegFloat, NonNegFloat] = Field(
        (8.0, 20.0), description="surge, sway linear drag (filter, surge: feedforward)")
    model_drag_quadratic_n_per_mps2: tuple[NonNegFloat, NonNegFloat] = Field(
        (27.7, 86.7), description="surge, sway quadratic drag (filter, surge: feedforward)")
    force_filter_tau_s: PositiveFloat = Field(4.0, le=120.0, description="smoothing of the steady force the heading follows")
    yaw_inertia_kgm2: PositiveFloat = Field(9.1, le=10000.0, description="I_z + N_rdot")
    yaw_bandwidth_radps: PositiveFloat = Field(0.8, le=20.0)
    yaw_damping_ratio: PositiveFloat = Field(1.0, le=5.0)
    min_heading_force_n: PositiveFloat = Field(1.0, le=1e4, description="below it the heading setpoint is kept")
    min_course_speed_mps: PositiveFloat = Field(0.1, le=5.0, description="slower: the followed course is kept")
    target_filter_tau_s: PositiveFloat = Field(3.0, le=120.0, description="smoothing of the followed point's velocity")
    navigation: SurfaceNavigationConfig = SurfaceNavigationConfig()
