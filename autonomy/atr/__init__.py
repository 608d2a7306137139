"""Onboard automatic target recognition on FLS frames (onnxruntime CNN, classical baseline)."""

import lazy_loader

# names resolved on first use, so importing one submodule (a config, say) loads no other
__getattr__, __dir__, __all__ = lazy_loader.attach(__name__, submod_attrs={
    "build": ["SHIPPED_MODEL_PATH", "build_detector"],
    "classical": ["ClassicalDetector"],
    "cnn_detector": ["CnnDetector"],
    "detector": ["Detector", "NullDetector"],
})
