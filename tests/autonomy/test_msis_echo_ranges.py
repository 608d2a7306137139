"""Echo ranges of a ping: leading edge against echo centre (hand-computed cases)."""

import numpy as np
import pytest

from autonomy.messages import MsisPing
from autonomy.msis.sonar_buffer import echo_ranges_m


def _ping(intensity: np.ndarray, spacing_m: float = 0.01) -> MsisPing:
    return MsisPing(t_s=0.0, angle_grad=0.0, step_grad=1, sample_period_ticks=80, sample_spacing_m=spacing_m,
                    transmit_duration_us=50.0, speed_of_sound_mps=1500.0, intensity=intensity.astype(np.uint8),
                    mount_pos_body_m=np.zeros(3), mount_rpy_rad=np.zeros(3))


def test_first_centre_is_the_weighted_centre_of_the_first_echo_and_first_its_leading_edge():
    x = np.zeros(600)
    x[100:141] = 200 + 50 * (1 - np.abs(np.arange(100, 141) - 120) / 20)  # a symmetric echo, 200..250..200
    x[400:410] = 255  # a second echo beyond the 0.3 m gap: not part of the first
    p = _ping(x)
    assert echo_ranges_m(p, 200, 0.5, "first") == pytest.approx([1.005])
    # weights x - 199 are symmetric about sample 120, so the centre is sample 120's middle
    assert echo_ranges_m(p, 200, 0.5, "first_centre") == pytest.approx([1.205])


def test_first_centre_bridges_gaps_shorter_than_min_gap_and_weights_by_excess_intensity():
    x = np.zeros(600)
    x[100], x[101], x[110] = 201, 201, 204  # a 9-sample gap (< 0.3 m): one echo
    w = np.array([2.0, 2.0, 5.0])
    k = np.array([100.5, 101.5, 110.5])
    assert echo_ranges_m(_ping(x), 200, 0.5, "first_centre") == pytest.approx([0.01 * (w @ k) / w.sum()])
    assert echo_ranges_m(_ping(np.zeros(600)), 200, 0.5, "first_centre").size == 0
    with pytest.raises(ValueError, match="first_centre"):
        echo_ranges_m(_ping(x), 200, 0.5, "last")
