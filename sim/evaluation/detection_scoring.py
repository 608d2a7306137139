"""In-mission ATR scoring as a mission observer, outside the perception stage.

Each perception result is matched to the visible targets of the frame it was made from
(greedy by score at :data:`sim.evaluation.detection_matching.MISSION_DETECTION_MATCH_IOU`,
:func:`sim.evaluation.detection_matching.match_frame`). The observer reads the ground truth
that rides with the sonar render; the loop itself never does, so leaving the observer out
(``auvsim run --no-scoring``, benchmarks) removes the scoring cost and changes nothing else.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from sim.evaluation.detection_matching import MISSION_DETECTION_MATCH_IOU, match_frame
from sim.events.records import MissionInfo, ObserverBase, PerceptionResult


class DetectionScorer(ObserverBase):
    """Counts true and false detections of the perception sonar's frames.

    Args:
        sonar_name: the sensor whose frames perception processes.
        detector: the detector's name, reported with the figures.

    ``last_true_detection`` holds, for the latest scored result, per detection whether it
    matched a visible target (observers after this one may colour detections by it).
    """

    sonar_truth = True  # matches detections to the frames' objects

    def __init__(self, sonar_name: str, detector: str) -> None:
        self.sonar_name = sonar_name
        self.detector = detector
        self.reset()

    def reset(self) -> None:
        self.n_frames = self.n_detections = self.n_true = self.n_false = 0
        self.n_visible_targets = self.n_hit_targets = 0
        self.last_true_detection: tuple[bool, ...] = ()
        self._truth = None

    # -- observer contract ------------------------------------------------------------
    def on_start(self, info: MissionInfo) -> None:
        self.reset()

    def on_step(self, record: Any) -> None:
        pass

    def on_message(self, name: str, msg: Any) -> None:
        if name != self.sonar_name:
            return
        if isinstance(msg, PerceptionResult):
            self._score(msg)
        elif hasattr(msg, "truth"):
            self._truth = msg.truth

    def on_end(self, summary: Any) -> None:
        pass

    # -- scoring ----------------------------------------------------------------------
    def _score(self, result: PerceptionResult) -> None:
        truth, self._truth = self._truth, None
        objects = truth.objects if truth is not None else ()
        gt = [o for o in objects if o.visible and o.is_target and o.bbox_xyxy is not None]
        dets = result.detections
        state, gt_hit = match_frame(np.array([d.box_xyxy_px for d in dets], dtype=float).reshape(-1, 4),
                                    np.array([d.score for d in dets], dtype=float),
                                    np.array([o.bbox_xyxy for o in gt], dtype=float).reshape(-1, 4),
                                    np.zeros(len(gt), dtype=bool), MISSION_DETECTION_MATCH_IOU)
        self.n_frames += 1
        self.n_visible_targets += len(gt)
        self.n_detections += len(dets)
        self.n_true += int(np.sum(state == 1))
        self.n_false += int(np.sum(state != 1))
        self.n_hit_targets += int(np.sum(gt_hit))
        self.last_true_detection = tuple(bool(s == 1) for s in state)

    def metrics(self) -> dict[str, Any]:
        """Detections, true and false ones, precision and recall of visible targets."""
        return {
            "detections": self.n_detections,
            "true_detections": self.n_true,
            "false_detections": self.n_false,
            "precision": self.n_true / self.n_detections if self.n_detections else None,
            "recall_visible_targets": self.n_hit_targets / self.n_visible_targets if self.n_visible_targets else None,
            "detector": self.detector,
        }
