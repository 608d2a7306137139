"""Automatic target recognition (ATR) config."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from autonomy.config_base import StrictModel


class ClassicalAtrConfig(StrictModel):
    """Contour detector after paper 004: blur, adaptive mean threshold, union-find clustering.

    Sizes are metric and converted to fan pixels with the frame's ``m_per_px``.
    """

    blur_sigma_m: float = Field(0.12, gt=0.0, le=5.0, description="Gaussian blur sigma")
    threshold_window_m: float = Field(2.0, gt=0.0, le=50.0, description="adaptive-mean window side")
    threshold_offset: float = Field(
        22.0, ge=0.0, le=255.0, description="grey levels above the local mean to be foreground"
    )
    cluster_distance_m: float = Field(0.5, ge=0.0, le=10.0, description="merge contours closer than this")
    min_size_m: float = Field(0.25, gt=0.0, le=20.0, description="smallest cluster extent kept")
    max_size_m: float = Field(4.0, gt=0.0, le=50.0, description="largest cluster extent kept")
    expected_size_m: float = Field(1.0, gt=0.0, le=20.0, description="typical target extent")
    contrast_scale: float = Field(
        40.0, gt=0.0, le=255.0, description="grey-level contrast giving a contrast score of ~0.63"
    )
    roi_radius_m: float | None = Field(
        None, gt=0.0, description="if set, candidates are weighted by distance to the ROI centre"
    )


class AtrConfig(StrictModel):
    """Detector selection, operating point and the sonar it reads.

    ``model_path`` ``None`` means the ONNX model shipped in ``autonomy/atr/models``. A CNN
    model knows the fan size it was trained on (its metadata); a scenario whose ATR sonar
    (``sonar_sensor``) makes fans of another size is refused at load unless
    ``accept_any_fan_size`` says to resize them.
    """

    detector: Literal["cnn", "classical", "none"] = "cnn"
    model_path: str | None = Field(None, description="ONNX model file; None = shipped model")
    score_threshold: float = Field(0.4, ge=0.0, le=1.0,
                                   description="operating threshold (validation sweep in models/MODEL_CARD.md)")
    nms_iou: float = Field(0.3, gt=0.0, le=1.0, description="IoU above which boxes are suppressed")
    max_detections: int = Field(50, ge=1, le=1000)
    intra_op_threads: int = Field(1, ge=1, le=64, description="onnxruntime CPU threads")
    classes: tuple[str, ...] | None = Field(
        None, description="keep only these class names (None = all the model knows)"
    )
    sonar_sensor: str | None = Field(
        None, min_length=1, description="sensor entry (kind fls) whose frames the survey's ATR and world model "
        "process; None = the first enabled fls entry. Other fls entries are rendered and recorded, not processed")
    accept_any_fan_size: bool = Field(
        False, description="cnn: run the model on a fan of another size than it was trained on, resized to its "
        "input (its detections there are not validated); False: such a scenario is refused at load")
    classical: ClassicalAtrConfig = ClassicalAtrConfig()
