"""Control configs: PID loops and the autopilots producing a body wrench.

Forces in N, moments in N m, angles in degrees in the config (converted to radians by the
consumers).
"""

from __future__ import annotations

from pydantic import Field

from autonomy.config_base import NonNegFloat, PositiveFloat, StrictModel


class PidConfig(StrictModel):
    """PID gains and limits (units of the loop: error unit -> N or N m)."""

    kp: NonNegFloat = 0.0
    ki: NonNegFloat = 0.0
    kd: NonNegFloat = 0.0
    integral_limit: NonNegFloat = Field(float("inf"), allow_inf_nan=True, description="max |ki * integral|, output units")
    output_limit: PositiveFloat = Field(float("inf"), allow_inf_nan=True, description="max |output|")
    output_rate_limit: PositiveFloat = Field(float("inf"), allow_inf_nan=True, description="max |d output/dt| per s")
    derivative_filter_tau_s: NonNegFloat = Field(0.0, le=60.0, description="first-order filter on D")


class ControlConfig(StrictModel):
    """Autopilots producing a body wrench [X, Y, Z, K, M, N] (K = M = 0).

    Defaults suit the FeelHippo estimate (about 35 kg, T100/T200-class thrusters).
    """

    surge: PidConfig = PidConfig(kp=120.0, ki=20.0, integral_limit=30.0, output_limit=40.0,
                                 output_rate_limit=120.0)
    sway: PidConfig = PidConfig(kp=80.0, ki=10.0, integral_limit=10.0, output_limit=12.0,
                                output_rate_limit=60.0)
    heading: PidConfig = PidConfig(kp=12.0, ki=0.5, kd=10.0, integral_limit=3.0, output_limit=12.0,
                                   output_rate_limit=40.0)
    depth: PidConfig = PidConfig(kp=120.0, ki=15.0, kd=150.0, integral_limit=10.0, output_limit=20.0,
                                 output_rate_limit=120.0)
    surge_feedforward_n_per_mps: NonNegFloat = Field(0.0, description="X += this * speed setpoint")
    heave_bias_n: float = Field(0.0, ge=-1000.0, le=1000.0, description="constant Z (e.g. buoyancy trim)")
    max_yaw_rate_dps: PositiveFloat = Field(15.0, le=360.0, description="heading reference slew limit")
    max_vertical_speed_mps: PositiveFloat = Field(0.3, le=5.0, description="depth reference slew limit")
    max_acceleration_mps2: PositiveFloat = Field(0.2, le=10.0, description="surge reference slew limit")
    altitude_filter_tau_s: NonNegFloat = Field(1.0, le=60.0, description="seabed-depth estimate filter")
