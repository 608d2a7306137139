"""Onboard automatic target recognition on FLS frames (onnxruntime CNN, classical baseline)."""

from autonomy.atr.build import SHIPPED_MODEL_PATH, build_detector
from autonomy.atr.classical import ClassicalDetector
from autonomy.atr.cnn_detector import CnnDetector
from autonomy.atr.detector import Detector, NullDetector

__all__ = ["SHIPPED_MODEL_PATH", "build_detector", "ClassicalDetector", "CnnDetector", "Detector",
           "NullDetector"]
