"""Precision is undefined without detections: ``eval-atr`` reports null ("n/a (no
detections)"), not 1, and its threshold sweep never chooses a threshold without a true
detection."""

from __future__ import annotations

import json

import pytest

from sim.cli import main
from sim.evaluation.atr_metrics import choose_threshold, evaluate_detector, threshold_sweep
from tests.support import write_fan_dataset


class _Blind:
    """Detects nothing."""

    def detect(self, frame, score_threshold=0.0):
        return []


@pytest.fixture
def blank_set(tmp_path):
    return write_fan_dataset(tmp_path / "blank")  # 4 uniform fans, one labelled opi each


def test_no_detections_leave_precision_undefined_and_recall_zero(blank_set):
    res = evaluate_detector(_Blind(), blank_set, 0.4)
    assert res["ground_truth"] == 4 and res["true_positives"] == res["false_positives"] == 0
    assert res["precision"] is None and res["recall"] == 0.0
    assert all(b["precision"] is None for b in res["by_range_band"])


def test_the_sweep_chooses_no_threshold_without_a_true_detection(blank_set):
    sweep = threshold_sweep(_Blind(), blank_set, [0.2, 0.5, 0.8])
    assert [r["precision"] for r in sweep] == [None, None, None]
    assert choose_threshold(sweep) is None
    # thresholds without a detection, or with recall 0, are never chosen over one that finds targets
    rows = [{"score_threshold": 0.2, "precision": 0.10, "recall": 0.50},
            {"score_threshold": 0.5, "precision": 0.0, "recall": 0.0},
            {"score_threshold": 0.8, "precision": None, "recall": 0.0}]
    assert choose_threshold(rows)["score_threshold"] == 0.2
    assert choose_threshold(rows[1:]) is None


def test_eval_atr_says_n_a_and_chooses_nothing(blank_set, capsys):
    # the contour detector finds no contour on a uniform fan
    assert main(["eval-atr", "--data", str(blank_set), "--detector", "classical", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["precision"] is None and res["recall"] == 0.0
    assert main(["eval-atr", "--data", str(blank_set), "--detector", "classical"]) == 0
    assert "precision                n/a (no detections)" in capsys.readouterr().out
    assert main(["eval-atr", "--data", str(blank_set), "--detector", "classical", "--sweep"]) == 0
    out = capsys.readouterr().out
    assert "<- chosen" not in out and "no threshold chosen" in out
    assert "precision n/a (no detections)  recall 0.000" in out
    assert main(["eval-atr", "--data", str(blank_set), "--detector", "classical", "--sweep", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["chosen"] is None and "no threshold chosen" in doc["note"]


def test_eval_atr_refuses_fans_of_another_size_than_the_model_and_side_scan_tiles(tmp_path, capsys):
    small = write_fan_dataset(tmp_path / "small", n_images=1, fan_hw=(240, 448))
    assert main(["eval-atr", "--data", str(small)]) == 2
    err = capsys.readouterr().err
    assert "--data" in err and "448 x 240 px" in err and "894 x 477" in err and "Traceback" not in err
    tiles = write_fan_dataset(tmp_path / "tiles", n_images=1)
    doc = json.loads((tiles / "annotations.json").read_text())
    for im in doc["images"]:
        im["sss_geometry"] = im.pop("fan_geometry")
    (tiles / "annotations.json").write_text(json.dumps(doc))
    assert main(["eval-atr", "--data", str(tiles), "--detector", "classical"]) == 2
    err = capsys.readouterr().err
    assert "side-scan tiles" in err and "Traceback" not in err
