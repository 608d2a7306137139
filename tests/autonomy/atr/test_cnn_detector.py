"""CNN detector: ONNX export matches torch, model-file and input checks, factory."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.atr import SHIPPED_MODEL_PATH, build_detector
from autonomy.atr.classical import ClassicalDetector
from autonomy.atr.cnn_detector import CnnDetector
from autonomy.atr.config import AtrConfig
from autonomy.atr.detector import NullDetector
from autonomy.atr.model_file import ModelFileError
from autonomy.messages import FlsFrame
from autonomy.sonar_geometry import FanGeometry

torch = pytest.importorskip("torch", reason="torch not installed: ONNX export tests need the train extra")

INPUT_HW = (64, 112)
FAN_HW = (128, 224)


def _frame(fan):
    geom = FanGeometry.fit(fan.shape[1], fan.shape[0], 1.0, 20.0, np.deg2rad(130.0)) if fan is not None and \
        getattr(fan, "ndim", 0) == 2 else FanGeometry.fit(224, 128, 1.0, 20.0, np.deg2rad(130.0))
    return FlsFrame(t_s=0.0, polar=np.zeros((1, 1), np.uint8), fan=fan, geometry=geom,
                    mount_pos_body_m=np.zeros(3), mount_rpy_rad=np.zeros(3))


@pytest.fixture(scope="module")
def tiny_model(tmp_path_factory):
    from sim.training.export import export_onnx
    from sim.training.model import CenterNetSmall

    torch.manual_seed(0)
    model = CenterNetSmall(2, width=8)
    # Non-trivial BN statistics so that eval-mode export is exercised.
    model.train()
    with torch.no_grad():
        for _ in range(3):
            model(torch.rand(4, 1, *INPUT_HW))
    model.eval()
    path = tmp_path_factory.mktemp("atr") / "tiny.onnx"
    export_onnx(model, path, INPUT_HW, FAN_HW, ["opi", "rock"])
    return model, path


def test_onnxruntime_matches_torch(tiny_model):
    model, path = tiny_model
    det = CnnDetector(path, score_threshold=0.0)
    rng = np.random.default_rng(0)
    fan = rng.integers(0, 256, FAN_HW, dtype=np.uint8)
    ort_out = det.raw_outputs(fan)
    with torch.no_grad():
        t_out = model.export_outputs(torch.from_numpy(det.preprocess(fan)))
    for name, t in zip(("size", "offset"), t_out[1:]):
        np.testing.assert_allclose(ort_out[name], t[0].numpy(), rtol=1e-4, atol=1e-5)
    # Heat-map: ORT peaks carry torch's sigmoid values, and ORT and torch agree on which cells
    # are 3x3 local maxima except for float near-ties (untrained nets have flat heat-maps).
    with torch.no_grad():
        logits, _, _ = model(torch.from_numpy(det.preprocess(fan)))
        full = torch.sigmoid(logits)[0].numpy()
        pooled = torch.nn.functional.max_pool2d(torch.sigmoid(logits), 3, 1, 1)[0].numpy()
    heat = ort_out["heatmap"]
    ort_peak, torch_peak = heat > 0, t_out[0][0].numpy() > 0
    np.testing.assert_allclose(heat[ort_peak], full[ort_peak], rtol=1e-4, atol=1e-6)
    clear = np.ones_like(full, dtype=bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            if dy or dx:
                nb = np.roll(np.roll(full, dy, axis=1), dx, axis=2)
                clear &= np.abs(full - nb) > 1e-5
    assert ort_peak.sum() > 0
    np.testing.assert_array_equal(ort_peak[clear], torch_peak[clear])
    np.testing.assert_array_equal(torch_peak[clear], np.isclose(full, pooled, rtol=0, atol=0)[clear])


def test_preprocess_follows_the_model_contract(tiny_model):
    """Input = the fan resized with cv2.INTER_AREA, / 255 in float32 (bit for bit the product
    with float32(1 / 255) the detector has always fed the model)."""
    import cv2

    _, path = tiny_model
    det = CnnDetector(path)
    fan = np.random.default_rng(3).integers(0, 256, FAN_HW, dtype=np.uint8)
    x = det.preprocess(fan)
    small = cv2.resize(fan, INPUT_HW[::-1], interpolation=cv2.INTER_AREA)
    assert x.shape == (1, 1, *INPUT_HW) and x.dtype == np.float32
    np.testing.assert_array_equal(x[0, 0], small.astype(np.float32) * np.float32(1.0 / 255.0))
    np.testing.assert_allclose(x[0, 0], small / 255.0, rtol=1e-7)


def test_detect_returns_messages_in_fan_pixels(tiny_model):
    _, path = tiny_model
    det = CnnDetector(path, score_threshold=0.0, max_detections=5)
    fan = np.random.default_rng(1).integers(0, 256, FAN_HW, dtype=np.uint8)
    dets = det.detect(_frame(fan))
    assert 0 < len(dets) <= 5
    for d in dets:
        assert d.class_name in ("opi", "rock") and 0.0 <= d.score <= 1.0
        assert d.box_xyxy_px.shape == (4,) and np.isfinite(d.range_m) and np.isfinite(d.azimuth_rad)
    assert [d.score for d in dets] == sorted([d.score for d in dets], reverse=True)
    only = CnnDetector(path, score_threshold=0.0, classes=("rock",)).detect(_frame(fan))
    assert all(d.class_name == "rock" for d in only)


def test_missing_model_file_is_named(tmp_path):
    missing = tmp_path / "nope.onnx"
    with pytest.raises(ModelFileError, match="nope.onnx.*no such file"):
        CnnDetector(missing)
    with pytest.raises(ModelFileError, match="nope.onnx.*no such file"):
        build_detector(AtrConfig(model_path=str(missing)))


def test_corrupt_model_file_is_named(tmp_path):
    bad = tmp_path / "corrupt.onnx"
    bad.write_bytes(b"\x08\x07not a protobuf at all" * 10)
    with pytest.raises(ValueError, match="corrupt.onnx.*not a valid ONNX"):
        CnnDetector(bad)


def test_foreign_onnx_model_is_rejected(tmp_path):
    import onnx
    from onnx import TensorProto, helper

    x = helper.make_tensor_value_info("x", TensorProto.FLOAT, [1, 3])
    y = helper.make_tensor_value_info("y", TensorProto.FLOAT, [1, 3])
    graph = helper.make_graph([helper.make_node("Relu", ["x"], ["y"])], "g", [x], [y])
    path = tmp_path / "foreign.onnx"
    onnx.save(helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)]), str(path))
    with pytest.raises(ValueError, match="foreign.onnx.*auvsim_atr_format"):
        CnnDetector(path)


def test_wrong_input_size_names_model_and_expected_size(tiny_model):
    _, path = tiny_model
    det = CnnDetector(path)
    with pytest.raises(ValueError, match=r"tiny.onnx.*128 x 224"):
        det.detect(_frame(np.zeros((100, 200), np.uint8)))
    with pytest.raises(ValueError, match="2-D uint8"):
        det.detect(_frame(np.zeros(FAN_HW, np.float64)))
    with pytest.raises(ValueError, match="2-D uint8"):
        det.detect(_frame(np.zeros((*FAN_HW, 3), np.uint8)))


def test_build_detector_kinds(tiny_model):
    _, path = tiny_model
    assert isinstance(build_detector(AtrConfig(detector="cnn", model_path=str(path))), CnnDetector)
    assert isinstance(build_detector(AtrConfig(detector="classical")), ClassicalDetector)
    assert isinstance(build_detector(AtrConfig(detector="none")), NullDetector)
    assert build_detector(AtrConfig(detector="none")).detect(_frame(np.zeros(FAN_HW, np.uint8))) == []


def test_shipped_model_loads():
    if not SHIPPED_MODEL_PATH.is_file():
        pytest.fail(f"shipped ATR model missing: {SHIPPED_MODEL_PATH}")
    det = build_detector(AtrConfig())
    assert det.fan_hw == (477, 894) and "opi" in det.class_names
    assert SHIPPED_MODEL_PATH.stat().st_size < 5 * 2**20
