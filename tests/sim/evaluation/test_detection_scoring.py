"""The in-mission ATR scoring observer, on hand-made frames whose matches are known."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from sim.evaluation.detection_scoring import DetectionScorer
from sim.events.records import PerceptionResult


def _obj(box, visible=True, is_target=True):
    return SimpleNamespace(bbox_xyxy=np.array(box, float), visible=visible, is_target=is_target)


def _det(box, score):
    return SimpleNamespace(box_xyxy_px=np.array(box, float), score=score)


def _render(*objects):
    return SimpleNamespace(truth=SimpleNamespace(objects=objects))


def test_counts_true_and_false_detections_against_visible_targets():
    sc = DetectionScorer("fls", "cnn")
    sc.on_start(None)
    # target A is hit (IoU 0.81), target B is missed, a rock and a hidden target do not count
    sc.on_message("fls", _render(_obj([10, 10, 30, 30]), _obj([100, 100, 120, 120]),
                                 _obj([200, 10, 220, 30], is_target=False), _obj([50, 50, 60, 60], visible=False)))
    sc.on_message("fls", PerceptionResult(0.0, detections=(_det([10, 12, 30, 32], 0.9), _det([200, 10, 220, 30], 0.8))))
    assert sc.last_true_detection == (True, False)
    sc.on_message("dvl", PerceptionResult(0.1, detections=(_det([0, 0, 1, 1], 0.9),)))  # another sensor: ignored
    sc.on_message("fls", _render())
    sc.on_message("fls", PerceptionResult(0.3))
    m = sc.metrics()
    assert (m["detections"], m["true_detections"], m["false_detections"]) == (2, 1, 1)
    assert m["precision"] == 0.5 and m["recall_visible_targets"] == 0.5 and m["detector"] == "cnn"
    assert sc.n_frames == 2 and sc.last_true_detection == ()


def test_no_detections_gives_no_precision():
    sc = DetectionScorer("fls", "classical")
    sc.on_message("fls", _render(_obj([10, 10, 30, 30])))
    sc.on_message("fls", PerceptionResult(0.0))
    assert sc.metrics()["precision"] is None and sc.metrics()["recall_visible_targets"] == 0.0
