"""An ATR model whose input pre-processing is folded into its graph (``input_transform:
fan_uint8``, ``scripts/atr_fold_input.py``) gives the unfolded model's outputs bit for bit."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from autonomy.atr.cnn_detector import CnnDetector

onnx = pytest.importorskip("onnx")  # the train extra (writing models); inference needs only onnxruntime

ROOT = Path(__file__).resolve().parents[3]
V3 = ROOT / "sim" / "training" / "checkpoints" / "atr_v3" / "atr_v3.onnx"


def _fold_script():
    spec = importlib.util.spec_from_file_location("atr_fold_input", ROOT / "scripts" / "atr_fold_input.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_folded_model_detects_exactly_as_the_padded_one(tmp_path):
    folded = tmp_path / "v3_folded.onnx"
    assert _fold_script().fold(V3, folded) == 0.0
    a, b = CnnDetector(V3, score_threshold=0.2), CnnDetector(folded, score_threshold=0.2)
    assert (a.input_transform, b.input_transform) == ("pad", "fan_uint8") and b.input_hw == b.fan_hw
    rng = np.random.default_rng(3)
    for _ in range(3):
        fan = (rng.random(a.fan_hw) * 80).astype(np.uint8)
        fan[200:230, 400:440] = 220  # a bright patch: something to detect
        ra, rb = a.raw_outputs(fan), b.raw_outputs(fan)
        assert all(np.array_equal(ra[k], rb[k]) for k in ra)
        da, db = a.detect_boxes(fan), b.detect_boxes(fan)  # the bound-buffer path
        assert all(np.array_equal(x, y) for x, y in zip(da, db))


def test_only_a_padded_model_folds(tmp_path):
    with pytest.raises(SystemExit, match="only 'pad' models fold"):
        _fold_script().fold(ROOT / "autonomy" / "atr" / "models" / "atr_centernet.onnx", tmp_path / "x.onnx")
    assert not (tmp_path / "x.onnx").exists()
