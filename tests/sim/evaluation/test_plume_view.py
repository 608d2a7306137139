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


def test_gating_counts_and_the_accepted_bubble_record():
    """Three clusters on one frame against hand geometry: the diver's (8 m, dead ahead), a
    breath 1 m beyond it in range (inside the ROI, let through by the gate) and one 10 deg to
    starboard (outside). Counted: two bubbles, one refused; one diver cluster, kept; the
    accepted bubble is recorded where it is, 1.0 m from the body axis, at normalised distance
    (1 / 1.5) / sqrt(2) from the ROI centre."""
    from autonomy.messages import Detection
    from autonomy.tracking.roi import PolarRoi

    stb = 8.0 * np.array([math.cos(math.radians(10.0)), math.sin(math.radians(10.0))])
    bubbles = np.array([[9.0, 0.0, 5.0], [stb[0], stb[1], 5.0]])
    ev = _evaluation((np.zeros(0), np.zeros((0, 1, 3)), np.zeros((0, 1), dtype=bool)))
    ev.bubbles_at = lambda t: bubbles
    cands = tuple(Detection(1.0, "diver", s, (0.0, 0.0, 1.0, 1.0), r, math.radians(a))
                  for r, a, s in [(8.0, 0.0, 0.9), (9.0, 0.0, 0.7), (8.0, 10.0, 0.8)])
    roi = PolarRoi(8.0, 0.0, 1.5, math.radians(5.0), np.eye(2))
    inside = roi.contains([8.0, 9.0, 8.0], np.radians([0.0, 0.0, 10.0]))
    feats = {"extent_m": np.array([1.6, 0.9, 0.5]), "area_m2": np.array([0.5, 0.3, 0.1])}
    res = SimpleNamespace(t_s=1.0, candidates=cands, roi={"fused": roi}, inside={"fused": inside},
                          accepted={"fused": inside}, chosen={"fused": cands[0]}, features=feats)
    ev._label(res)
    assert (ev.n_bubble, ev.n_bubble_rejected, ev.n_target, ev.n_target_kept) == (2, 1, 1, 1)
    (rec,) = ev.accepted_bubbles
    assert rec["range_m"] == 9.0 and rec["azimuth_deg"] == 0.0 and not rec["chosen"]
    assert abs(rec["body_distance_m"] - 1.0) < 1e-9 and rec["bubble_distance_m"] < 1e-9
    assert abs(rec["roi_centre_distance_normalised"] - (1.0 / 1.5) / math.sqrt(2.0)) < 1e-9
    assert rec["extent_m"] == 0.9 and rec["target_clusters_on_frame"] == 1
