"""Detector interface and the conversion of fan-image boxes to :class:`Detection` messages."""

from __future__ import annotations

from typing import Protocol, Sequence

import numpy as np
from numpy.typing import NDArray

from autonomy.atr.reference_point import box_reference_polar
from autonomy.messages import Detection, FlsFrame


class Detector(Protocol):
    """Anything that turns one FLS frame into detections.

    Attributes:
        class_names: the class labels its detections carry (the class table of the
            detection messages; a one-class detector: its one label).
    """

    class_names: tuple[str, ...]

    def detect(self, frame: FlsFrame) -> list[Detection]:
        ...


class NullDetector:
    """``detector: none``: never detects anything."""

    class_names: tuple[str, ...] = ("target",)

    def detect(self, frame: FlsFrame) -> list[Detection]:
        check_frame(frame, None)
        return []


def check_frame(frame: FlsFrame, expected_hw: tuple[int, int] | None, source: str = "detector") -> None:
    """Raise ``ValueError`` unless ``frame.fan`` is a 2-D uint8 image of ``expected_hw``."""
    fan = getattr(frame, "fan", None)
    if not isinstance(fan, np.ndarray) or fan.ndim != 2 or fan.dtype != np.uint8:
        desc = "missing" if fan is None else f"{getattr(fan, 'dtype', type(fan))} {getattr(fan, 'shape', '')}"
        want = f"{expected_hw[0]} x {expected_hw[1]} (height x width)" if expected_hw else "(height, width)"
        raise ValueError(f"{source}: expects FlsFrame.fan as a 2-D uint8 image {want}, got {desc}")
    if expected_hw is not None and fan.shape != tuple(expected_hw):
        raise ValueError(
            f"{source}: expects a fan image of {expected_hw[0]} x {expected_hw[1]} px "
            f"(height x width), got {fan.shape[0]} x {fan.shape[1]}"
        )


def to_detections(frame: FlsFrame, boxes_xyxy: NDArray, scores: NDArray,
                  class_names: Sequence[str]) -> list[Detection]:
    """Build messages for N boxes (N, 4) in fan px with scores (N,) and class names (N,)."""
    boxes = np.asarray(boxes_xyxy, dtype=np.float64).reshape(-1, 4)
    if boxes.shape[0] == 0:
        return []
    range_m, az_rad = box_reference_polar(boxes, frame.geometry)
    return [
        Detection(t_s=float(frame.t_s), class_name=str(c), score=float(s),
                  box_xyxy_px=boxes[i].copy(), range_m=float(range_m[i]), azimuth_rad=float(az_rad[i]))
        for i, (s, c) in enumerate(zip(scores, class_names))
    ]
