"""The tracking evaluation's view of the bubble plume, against hand geometry: a horizontal
sonar at the origin looking north, a diver lying east-west 8 m ahead at the sonar's depth;
the 14 deg vertical beam is +-0.98 m high there."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from sim.evaluation.tracking_eval import TrackingEvaluation

DIVER = np.array([8.0, 0.0, 5.0])


def _evaluation(breaths):
    ev = TrackingEvaluation(None, lambda t: DIVER, None, np.zeros(3), np.eye(3), math.radians(30.0), (1.0, 15.0),
                            math.radians(14.0), target_axis_at=lambda t: np.stack([DIVER - [0, 0.7, 0],
                                                                                   DIVER + [0, 0.7, 0]]),
                            breaths_at=lambda t: breaths, plume_apart_m=0.76)
    ev._poses[1000] = (np.array([0.0, 0.0, 5.0]), np.eye(3))
    return ev


def test_breaths_in_the_beam_and_apart_from_the_body():
    half_beam_m = 8.0 * math.tan(math.radians(7.0))  # 0.982 m
    pts = np.array([
        [[8.0, 0.5, 5.0 - 0.5], [8.1, 0.4, 5.0 - 0.6]],  # over the body, in the beam: in view, not apart
        [[8.0, 1.6, 5.0 - 0.5], [8.0, 1.2, 5.0 - 0.4]],  # 0.5-0.9 m past the diver's feet in azimuth: not apart
        [[8.0, 1.6, 5.0 - 0.5], [8.0, 1.5, 5.0 - 0.4]],  # 0.8-0.9 m past them: apart
        [[9.0, 0.0, 5.0 - 0.5], [9.0, 0.0, 5.0 - 0.4]],  # 1 m beyond it in range: apart
        [[8.0, 2.0, 5.0 - half_beam_m - 0.1], [8.0, 2.0, 5.0 - half_beam_m - 0.3]],  # above the beam: unseen
        [[8.0, 2.0, 5.0 - 0.2], [8.0, 2.0, 5.0 - 0.3]],  # surfaced (mask): unseen
    ])
    wet = np.array([[True, True], [True, True], [True, True], [True, True], [True, True], [False, False]])
    ages = np.array([1.0, 2.0, 2.5, 3.0, 5.0, 6.0])
    ev = _evaluation((ages, pts, wet))
    ev._plume_view(SimpleNamespace(t_s=1.0))
    m = ev.plume_metrics()
    assert m["frames"] == 1 and m["breath_frames_in_view"] == 4 and m["breath_frames_apart"] == 2
    assert m["breaths_seen"] == 4 and m["last_in_view_age_max_s"] == 3.0
    # nearest in-view bubble to the body axis in the sonar plane: ~0.1 (over it), 0.5 and 0.8 (past the feet), 1.0 (beyond)
    assert abs(m["nearest_to_body_median_m"] - 0.65) < 0.02  # median of ~0.1, 0.5, 0.8, 1.0
