"""End-to-end: tiny generated dataset -> train-atr -> ONNX -> detector -> eval-atr figures."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("torch", reason="torch not installed: training needs the `train` extra")

from autonomy.atr.cnn_detector import CnnDetector  # noqa: E402
from sim.evaluation.atr_metrics import evaluate_detector  # noqa: E402
from sim.dataset.generate import RenderSettings, generate_dataset  # noqa: E402
from sim.dataset.randomization import Randomization  # noqa: E402
from sim.training.train import TrainParams, train_atr  # noqa: E402

FAST = Randomization(range_max_m=(12.0, 16.0), n_targets=(1, 3), n_distractors=(0, 1), frames_per_scene=3,
                     seabed_kinds=("plane",))


@pytest.fixture(scope="module")
def tiny_dataset(tmp_path_factory):
    d = tmp_path_factory.mktemp("train") / "data"
    generate_dataset(d, 6, seed=11, workers=1, randomization=FAST,
                     settings=RenderSettings(azimuth_columns=181, elevation_rays=12), progress=False)
    return d


def test_train_export_detect_and_evaluate(tiny_dataset, tmp_path):
    out = tmp_path / "tiny.onnx"
    params = TrainParams(input_hw=(96, 176), width=8, epochs=3, batch_size=3, threads=1, max_minutes=1.0)
    summary = train_atr(tiny_dataset, out, params, log=lambda *_: None)
    assert summary["epochs_run"] == 3 and out.is_file()
    assert all(np.isfinite(h["heat"]) for h in summary["history"])
    det = CnnDetector(out, score_threshold=0.0)
    assert det.class_names == ("opi", "rock", "debris") and det.input_hw == (96, 176)
    assert det.fan_hw == (477, 894)
    meta = json.loads(det._session.get_modelmeta().custom_metadata_map["train_data"])
    assert meta["seed"] == 11 and meta["n_images"] == 6
    res = evaluate_detector(det, tiny_dataset, score_threshold=0.3)
    assert res["frames"] == 6 and res["ground_truth"] > 0
    for k in ("recall", "ap50", "ap50_95", "false_alarms_per_frame", "frames_per_s"):
        assert np.isfinite(res[k]), k
    # precision is undefined (None) exactly when the model made no detection at the threshold
    n_det = res["true_positives"] + res["false_positives"]
    assert (res["precision"] is None) == (n_det == 0) and (n_det == 0 or np.isfinite(res["precision"]))
    coco = json.loads((tiny_dataset / "annotations.json").read_text())
    with_objects = {a["image_id"] for a in coco["annotations"] if not a["iscrowd"]}
    assert summary["check"]["frames"] == len(with_objects) and not summary["check"]["held_out"]


def test_training_reduces_the_loss(tiny_dataset, tmp_path):
    # a generous time budget: the schedule then follows the steps, not the machine's speed
    params = TrainParams(input_hw=(96, 176), width=8, epochs=12, batch_size=6, lr=1e-2, threads=1, max_minutes=30.0)
    summary = train_atr(tiny_dataset, tmp_path / "m.onnx", params, log=lambda *_: None)
    heat = [h["heat"] for h in summary["history"]]
    assert heat[-1] < 0.7 * heat[0], heat  # about 0.5-0.57 of the first epoch


def test_train_on_a_folder_without_annotations_names_it(tmp_path):
    with pytest.raises(FileNotFoundError, match="annotations.json"):
        train_atr(tmp_path, tmp_path / "x.onnx", TrainParams(), log=lambda *_: None)


def test_a_resumed_run_takes_the_same_steps_as_an_unbroken_one(tiny_dataset, tmp_path):
    import onnxruntime as ort
    from sim.training.train import CheckpointError

    params = TrainParams(input_hw=(96, 176), width=8, epochs=3, batch_size=2, threads=1, max_minutes=1e6)
    whole = train_atr(tiny_dataset, tmp_path / "whole.onnx", params, log=lambda *_: None)
    ckpt = tmp_path / "run.ckpt"
    # stop after the first step (a deadline already passed), then resume twice more
    first = train_atr(tiny_dataset, tmp_path / "part.onnx", params, log=lambda *_: None, checkpoint=ckpt,
                      stop_after_minutes=1e-9)
    assert not first["finished"] and first["steps"] == 1 and ckpt.is_file()
    second = train_atr(tiny_dataset, tmp_path / "part.onnx", params, log=lambda *_: None, checkpoint=ckpt,
                       resume=True, stop_after_minutes=1e-9)
    assert second["steps"] == 2
    # the third stop falls on the end of the first epoch (6 images, batch 2): the checkpoint
    # then holds no epoch order
    third = train_atr(tiny_dataset, tmp_path / "part.onnx", params, log=lambda *_: None, checkpoint=ckpt,
                      resume=True, stop_after_minutes=1e-9)
    assert third["steps"] == 3 and len(third["history"]) == 1
    rest = train_atr(tiny_dataset, tmp_path / "part.onnx", params, log=lambda *_: None, checkpoint=ckpt, resume=True)
    assert rest["finished"] and rest["steps"] == whole["steps"] == whole["total_steps"]
    assert [h["heat"] for h in rest["history"]] == pytest.approx([h["heat"] for h in whole["history"]], rel=1e-5)
    x = {"image": np.random.default_rng(0).random((1, 1, 96, 176), dtype=np.float32)}
    a = ort.InferenceSession(str(tmp_path / "whole.onnx")).run(None, x)
    b = ort.InferenceSession(str(tmp_path / "part.onnx")).run(None, x)
    for u, v in zip(a, b):
        np.testing.assert_allclose(u, v, atol=1e-5)
    other = TrainParams(input_hw=(96, 176), width=8, epochs=3, batch_size=2, threads=1, max_minutes=1e6, lr=1e-2)
    with pytest.raises(CheckpointError, match=r"lr 0\.003 -> 0\.01"):
        train_atr(tiny_dataset, tmp_path / "x.onnx", other, log=lambda *_: None, checkpoint=ckpt, resume=True)


def test_stride8_model_at_native_resolution_pads_the_fan(tiny_dataset, tmp_path):
    out = tmp_path / "s8.onnx"
    params = TrainParams(input_hw=(480, 896), crop_hw=(96, 160), width=8, epochs=1, batch_size=3, threads=1,
                         arch="s8", input_transform="pad", light_heads=True)
    train_atr(tiny_dataset, out, params, log=lambda *_: None)
    det = CnnDetector(out, score_threshold=0.0, max_detections=5)
    assert det.input_transform == "pad" and det.stride == 8 and det.input_hw == (480, 896)
    fan = np.random.default_rng(1).integers(0, 255, det.fan_hw, dtype=np.uint8)
    x = det.preprocess(fan)
    # the fan sits unresized in the top-left corner, zeros beyond
    np.testing.assert_array_equal(x[0, 0, :477, :894], fan.astype(np.float32) * np.float32(1 / 255))
    assert not x[0, 0, 477:].any() and not x[0, 0, :, 894:].any()
    # the bound (allocation-free) path and the plain one give the same boxes, in fan px unscaled
    with det._lock:
        bound = {k: v.copy() for k, v in det._run_bound(fan).items()}
    plain = det.raw_outputs(fan)
    for k in plain:
        np.testing.assert_array_equal(bound[k], plain[k])
    boxes, _, _ = det.detect_boxes(fan)
    assert boxes.shape[0] == 5 and (boxes[:, :2] > -50).all() and (boxes[:, 2:] < 950).all()


def test_a_checkpoint_from_before_augment_was_a_parameter_resumes_as_basic(tiny_dataset, tmp_path):
    import torch

    params = TrainParams(input_hw=(96, 176), width=8, epochs=2, batch_size=2, threads=1, max_minutes=1e6)
    ckpt = tmp_path / "old.ckpt"
    train_atr(tiny_dataset, tmp_path / "a.onnx", params, log=lambda *_: None, checkpoint=ckpt, stop_after_minutes=1e-9)
    state = torch.load(ckpt, weights_only=False)
    del state["params"]["augment"]  # as written before the parameter existed
    torch.save(state, ckpt)
    done = train_atr(tiny_dataset, tmp_path / "a.onnx", params, log=lambda *_: None, checkpoint=ckpt, resume=True)
    assert done["finished"]
    lines: list[str] = []  # resuming a finished run trains nothing and says so
    again = train_atr(tiny_dataset, tmp_path / "a.onnx", params, log=lines.append, checkpoint=ckpt, resume=True)
    assert again["steps"] == done["steps"] and any("holds a finished run" in x for x in lines), lines
    from sim.training.train import CheckpointError

    with pytest.raises(CheckpointError, match="augment 'basic' -> 'sonar'"):
        train_atr(tiny_dataset, tmp_path / "b.onnx", TrainParams(**{**params.__dict__, "augment": "sonar"}),
                  log=lambda *_: None, checkpoint=ckpt, resume=True)
