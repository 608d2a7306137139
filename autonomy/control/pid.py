"""Discrete PID controller with anti-windup, derivative on measurement and output limits."""

from __future__ import annotations

import math

from autonomy.control.config import PidConfig


class Pid:
    """``u = kp e + ki integral(e) - kd d(measurement)/dt`` with limits.

    * Derivative on measurement (no kick on setpoint steps); callers with a measured rate
      pass it as ``measurement_rate`` instead of differencing.
    * Anti-windup: the integral is clamped so ``|ki * integral| <= integral_limit`` and is
      frozen (conditional integration) while the output is saturated in the direction of
      the error.
    * The output is clipped to ``output_limit`` and slewed at most ``output_rate_limit``
      per second.
    """

    def __init__(self, gains: PidConfig) -> None:
        self.gains = gains
        self.reset()

    def reset(self, output: float = 0.0) -> None:
        """Forget the integral and derivative history; start slewing from ``output``."""
        self.integral = 0.0
        self.output = float(output)
        self._prev_measurement: float | None = None
        self._d_filtered = 0.0

    def update(
        self,
        error: float,
        measurement: float,
        dt_s: float,
        measurement_rate: float | None = None,
        feedforward: float = 0.0,
    ) -> float:
        """One step. ``error`` = setpoint - measurement (already wrapped for angles).

        Args:
            error: control error in loop units.
            measurement: measured value, differentiated when ``measurement_rate`` is None.
            dt_s: time since the previous call, > 0.
            measurement_rate: measured d(measurement)/dt, if available.
            feedforward: added to the PID terms before saturation.

        Returns:
            The limited output.
        """
        if not dt_s > 0.0:
            raise ValueError(f"dt_s must be > 0, got {dt_s}")
        g = self.gains

        if measurement_rate is None:
            rate = 0.0 if self._prev_measurement is None else (measurement - self._prev_measurement) / dt_s
        else:
            rate = float(measurement_rate)
        self._prev_measurement = float(measurement)
        if g.derivative_filter_tau_s > 0.0:
            alpha = dt_s / (g.derivative_filter_tau_s + dt_s)
            self._d_filtered += alpha * (rate - self._d_filtered)
        else:
            self._d_filtered = rate

        p_term = g.kp * error
        d_term = -g.kd * self._d_filtered

        # Conditional integration: only integrate if it does not push a saturated output further.
        candidate = self.integral + error * dt_s
        if g.ki > 0.0:
            i_max = g.integral_limit / g.ki
            candidate = min(max(candidate, -i_max), i_max)
            unsat = p_term + g.ki * candidate + d_term + feedforward
            if abs(unsat) > g.output_limit and math.copysign(1.0, unsat) == math.copysign(1.0, error):
                candidate = self.integral if abs(candidate) > abs(self.integral) else candidate
            self.integral = candidate
        i_term = g.ki * self.integral

        raw = p_term + i_term + d_term + feedforward
        raw = min(max(raw, -g.output_limit), g.output_limit)
        max_step = g.output_rate_limit * dt_s
        self.output = self.output + min(max(raw - self.output, -max_step), max_step)
        return self.output
