"""Detector factory from :class:`AtrConfig`."""

from __future__ import annotations

from pathlib import Path

from autonomy.atr.classical import ClassicalDetector
from autonomy.atr.cnn_detector import CnnDetector
from autonomy.atr.config import AtrConfig
from autonomy.atr.detector import Detector, NullDetector

SHIPPED_MODEL_PATH = Path(__file__).resolve().parent / "models" / "atr_centernet.onnx"


def shipped_model_names() -> tuple[str, ...]:
    """Names of the models shipped in ``autonomy/atr/models/`` (file stems)."""
    return tuple(sorted(p.stem for p in SHIPPED_MODEL_PATH.parent.glob("*.onnx")))


def resolve_model(name_or_path: str | Path) -> Path:
    """The ONNX file a user names: a path, or the name of a shipped model
    (:func:`shipped_model_names`, e.g. ``atr_centernet``). A path that exists wins; the
    returned path need not exist (the caller reports a missing file)."""
    p = Path(name_or_path).expanduser()
    text = str(name_or_path)
    if p.exists() or "/" in text or "\\" in text or text.endswith(".onnx"):
        return p
    shipped = SHIPPED_MODEL_PATH.parent / f"{text}.onnx"
    return shipped if shipped.is_file() else p


def model_path(cfg: AtrConfig) -> Path:
    """The ONNX file ``cfg`` selects (the shipped model when ``model_path`` is None)."""
    return SHIPPED_MODEL_PATH if cfg.model_path is None else resolve_model(cfg.model_path)


def build_detector(cfg: AtrConfig) -> Detector:
    """The detector ``cfg.detector`` names, at ``cfg``'s operating point."""
    if cfg.detector == "cnn":
        return CnnDetector(model_path(cfg), score_threshold=cfg.score_threshold, nms_iou=cfg.nms_iou,
                           max_detections=cfg.max_detections, intra_op_threads=cfg.intra_op_threads,
                           classes=cfg.classes, accept_any_fan_size=cfg.accept_any_fan_size)
    if cfg.detector == "classical":
        return ClassicalDetector(cfg.classical, score_threshold=cfg.score_threshold,
                                 max_detections=cfg.max_detections)
    return NullDetector()
