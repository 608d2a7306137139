"""Ping360 device arithmetic: sample period, range, transmit duration and ping duration.

The device samples the echo every ``sample_period`` ticks of 25 ns; ``number_of_samples``
samples cover the two-way travel time to the range, so
``range = number_of_samples * c * 25 ns * sample_period / 2`` ([Ping360] in
``docs/references.md``). The sample period is at least 80 ticks
(and a 16-bit count), the transmit duration 5-500 us and at most 64 sample periods; at most
1200 samples per ping. The automatic transmit duration is the device software's rule
``max(4000 range / c, 1.25 sample period)`` us, clipped to those limits.

Ping duration (the time from one ping to the next) is the project's model of the head's
cycle: the motor step, the transmission, the receive window ``2 range / c`` and a fixed
processing / transfer overhead,
``T = step_grad * motor_s_per_grad + transmit_duration + number_of_samples * sample_period
* 25 ns + overhead_s``; it grows with the range as the device's does. The motor and overhead
defaults (2.5 ms per gradian, 4 ms) are the project's estimate: a 400-step turn at 12 m then
takes about 9 s, inside the 8-20 s of the device at pool ranges.
"""

from __future__ import annotations

import math

TICK_S = 25e-9  #: sample-period tick, s
MIN_SAMPLE_PERIOD_TICKS = 80
MAX_SAMPLE_PERIOD_TICKS = 65535
MAX_SAMPLES = 1200
MIN_TRANSMIT_US = 5.0
MAX_TRANSMIT_US = 500.0
GRAD_PER_TURN = 400


def sample_period_ticks(range_m: float, number_of_samples: int, speed_of_sound_mps: float) -> int:
    """Sample period (ticks of 25 ns, rounded) that puts ``number_of_samples`` over ``range_m``.

    ``round(2 range / (n c 25 ns))``. Not clipped: callers check it against
    :data:`MIN_SAMPLE_PERIOD_TICKS` and :data:`MAX_SAMPLE_PERIOD_TICKS`.

    Raises:
        ValueError: a non-positive range, sample count or speed of sound.
    """
    if not (range_m > 0.0 and number_of_samples > 0 and speed_of_sound_mps > 0.0):
        raise ValueError("range_m, number_of_samples and speed_of_sound_mps must be positive")
    return int(round(2.0 * range_m / (number_of_samples * speed_of_sound_mps * TICK_S)))


def range_m(number_of_samples: int, sample_period: int, speed_of_sound_mps: float) -> float:
    """One-way range (m) the samples cover: ``n c 25 ns sample_period / 2``."""
    return number_of_samples * speed_of_sound_mps * TICK_S * sample_period / 2.0


def sample_spacing_m(sample_period: int, speed_of_sound_mps: float) -> float:
    """Range between consecutive samples, m: ``c 25 ns sample_period / 2``."""
    return speed_of_sound_mps * TICK_S * sample_period / 2.0


def max_transmit_us(sample_period: int) -> float:
    """Longest transmit the firmware allows at this sample period: ``min(500, 64 period)`` us."""
    return min(MAX_TRANSMIT_US, 64.0 * sample_period * TICK_S * 1e6)


def auto_transmit_us(range_m_: float, sample_period: int, speed_of_sound_mps: float) -> float:
    """Automatic transmit duration, us: ``max(4000 range / c, 1.25 period)`` clipped to
    ``[5, max_transmit_us(period)]``."""
    period_us = sample_period * TICK_S * 1e6
    auto = max(round(4000.0 * range_m_ / speed_of_sound_mps), 1.25 * period_us)
    return float(max(MIN_TRANSMIT_US, min(max_transmit_us(sample_period), auto)))


def ping_duration_s(step_grad: int, transmit_us: float, number_of_samples: int, sample_period: int,
                    motor_s_per_grad: float, overhead_s: float) -> float:
    """Time from one ping to the next, s (module docstring):
    ``step_grad motor_s_per_grad + transmit + n sample_period 25 ns + overhead_s``."""
    return (step_grad * motor_s_per_grad + transmit_us * 1e-6 + number_of_samples * sample_period * TICK_S
            + overhead_s)


def grad_to_rad(angle_grad: float) -> float:
    """Gradians (400 per turn) -> radians."""
    return angle_grad * (2.0 * math.pi / GRAD_PER_TURN)
