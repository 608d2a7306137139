"""``train-atr`` refuses classes it could not learn before any training (exit 2, naming the
classes present) and warns when the model it wrote detects nothing on its check frames."""

from __future__ import annotations

import json

import pytest

pytest.importorskip("torch", reason="torch not installed: training needs the `train` extra")

from sim.cli import main  # noqa: E402
from tests.support import write_fan_dataset  # noqa: E402

TINY = ["--input", "96x176", "--crop", "none", "--width", "4", "--epochs", "1", "--batch-size", "4",
        "--threads", "1"]


@pytest.fixture
def data(tmp_path):
    return write_fan_dataset(tmp_path / "d", n_images=4, fan_hw=(160, 300))  # opi and rock labelled, no debris


@pytest.mark.parametrize("classes,named", [
    ("mine", "no labelled object of class mine"),
    ("opi,debris", "no labelled object of class debris"),
    ("opi,opi", "names opi more than once"),
    ("opi,", "empty class name"),
])
def test_classes_not_in_the_data_are_refused_before_training(data, tmp_path, capsys, monkeypatch, classes, named):
    import sim.training.train as train

    monkeypatch.setattr(train, "_load_all", lambda *a, **k: pytest.fail("images loaded for training"))
    out = tmp_path / "m.onnx"
    code = main(["train-atr", "--data", str(data), "--out", str(out), "--classes", classes, *TINY])
    err = capsys.readouterr().err
    assert code == 2, err
    assert named in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    if "no labelled" in named:
        assert "classes present: opi (4 labelled), rock (4 labelled)" in err
    assert not out.exists()


def test_datasets_of_different_fans_are_refused_before_training(data, tmp_path, capsys):
    other = write_fan_dataset(tmp_path / "o", n_images=2, fan_hw=(120, 300))
    code = main(["train-atr", "--data", f"{data},{other}", "--out", str(tmp_path / "m.onnx"), *TINY])
    err = capsys.readouterr().err
    assert code == 2 and "fans of different sizes" in err and "300 x 120 px" in err, err


def test_a_model_that_detects_nothing_is_written_with_a_warning(data, tmp_path, capsys):
    from autonomy.atr.cnn_detector import CnnDetector
    from autonomy.atr.config import AtrConfig
    from sim.evaluation.atr_metrics import frame_from_record

    out = tmp_path / "m.onnx"
    val = write_fan_dataset(tmp_path / "val", n_images=3, fan_hw=(160, 300))
    code = main(["train-atr", "--data", str(data), "--val-data", str(val), "--out", str(out), *TINY])
    captured = capsys.readouterr()
    assert code == 0 and out.is_file()
    # the warning's figure, counted independently: the written model on the validation frames
    import cv2

    det = CnnDetector(out, score_threshold=AtrConfig().score_threshold)
    recs = json.loads((val / "annotations.json").read_text())["images"]
    n = sum(len(det.detect(frame_from_record(r, cv2.imread(str(val / r["file_name"]), cv2.IMREAD_GRAYSCALE))))
            for r in recs)
    assert n == 0  # one epoch of a 4-channel model stays near its prior (score 0.1 < 0.4)
    assert ("warning: the model in" in captured.err and "detects nothing at score threshold 0.40 on 3 validation "
            "frames holding 6 labelled objects" in captured.err), captured.err
    assert "makes 0 detections on 3 validation frames" in captured.out


@pytest.mark.parametrize("case", ["resume_without_checkpoint", "resume_missing", "checkpoint_exists",
                                  "checkpoint_folder", "other_parameters"])
def test_checkpoint_misuse_gets_one_line_and_keeps_what_was_written(data, tmp_path, capsys, case):
    out, ckpt = tmp_path / "m.onnx", tmp_path / "run.ckpt"
    if case in ("checkpoint_exists", "other_parameters"):
        assert main(["train-atr", "--data", str(data), "--out", str(out), "--checkpoint", str(ckpt), *TINY]) == 0
        capsys.readouterr()
    before = ckpt.read_bytes() if ckpt.exists() else None
    args = {"resume_without_checkpoint": ["--resume"],
            "resume_missing": ["--checkpoint", str(ckpt), "--resume"],
            "checkpoint_exists": ["--checkpoint", str(ckpt)],
            "checkpoint_folder": ["--checkpoint", str(tmp_path)],
            "other_parameters": ["--checkpoint", str(ckpt), "--resume", "--lr", "0.01"]}[case]
    code = main(["train-atr", "--data", str(data), "--out", str(tmp_path / "n.onnx"), *TINY, *args])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert {"resume_without_checkpoint": "--resume: name the checkpoint",
            "resume_missing": "no such file to resume from",
            "checkpoint_exists": "pass --resume to continue",
            "checkpoint_folder": "is a folder",
            "other_parameters": "lr 0.003 -> 0.01"}[case] in err
    assert (ckpt.read_bytes() if ckpt.exists() else None) == before


def test_init_from_starts_a_run_from_another_runs_network_and_refuses_a_misfit(data, tmp_path, capsys):
    import torch

    from sim.training.train import CHECKPOINT_FORMAT

    pre = tmp_path / "pre.ckpt"
    assert main(["train-atr", "--data", str(data), "--out", str(tmp_path / "pre.onnx"), "--checkpoint", str(pre),
                 *TINY]) == 0
    state = torch.load(pre, map_location="cpu", weights_only=False)
    assert state["format"] == CHECKPOINT_FORMAT and state["class_names"] == ["opi", "rock", "debris"]
    # fine-tuning with steps of no size (a learning rate of 1e-30) keeps the pretrained weights
    # (the batch-norm statistics move with the new data, as they should)
    tuned = tmp_path / "tuned.ckpt"
    assert main(["train-atr", "--data", str(data), "--out", str(tmp_path / "tuned.onnx"), "--init-from", str(pre),
                 "--checkpoint", str(tuned), *TINY, "--lr", "1e-30"]) == 0
    a, b = state["model"], torch.load(tuned, map_location="cpu", weights_only=False)["model"]
    learnt = [k for k in a if "running_" not in k and "num_batches" not in k]
    assert len(learnt) > 10 and all(torch.allclose(a[k], b[k], atol=1e-7) for k in learnt)
    fresh = tmp_path / "fresh.ckpt"  # the same run without --init-from starts elsewhere
    assert main(["train-atr", "--data", str(data), "--out", str(tmp_path / "fresh.onnx"), "--checkpoint", str(fresh),
                 *TINY, "--lr", "1e-30", "--seed", "5"]) == 0
    c = torch.load(fresh, map_location="cpu", weights_only=False)["model"]
    assert not all(torch.allclose(a[k], c[k], atol=1e-7) for k in learnt)
    for argv, named in ((["--width", "6"], "its network differs: width 4 (this run: 6)"),
                        (["--resume", "--checkpoint", str(pre)], "give one"),
                        (["--init-from", str(tmp_path / "nope.ckpt")], "no such checkpoint file")):
        capsys.readouterr()
        extra = [] if "--init-from" in argv else ["--init-from", str(pre)]
        code = main(["train-atr", "--data", str(data), "--out", str(tmp_path / "x.onnx"), *TINY, *argv, *extra])
        err = capsys.readouterr().err
        assert code == 2 and named in err and len(err.strip().splitlines()) == 1, err
