"""``auvsim eval-atr``: precision, recall and AP of the ATR detector on a held-out set."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from sim.cli.args import positive_int, probability
from sim.cli.errors import CliError
from autonomy.atr.model_file import ModelFileError
from sim.dataset.errors import DatasetError, fls_fan_hw, require_dataset


def _fmt(v) -> str:
    return "-" if v is None else (f"{v:.3f}" if isinstance(v, float) else str(v))


#: How the console shows a precision that is undefined (no detection at the threshold).
NO_DETECTIONS = "n/a (no detections)"


def _detector_config(args: argparse.Namespace):
    from autonomy.atr.build import model_path, shipped_model_names
    from autonomy.atr.config import AtrConfig

    if args.model is not None and args.detector != "cnn":
        raise CliError(f"--model applies to the cnn detector; --detector {args.detector} has no model file")
    if args.model is not None and Path(args.model).expanduser().is_dir():
        raise ModelFileError(f"--model {args.model}: is a folder; name the ONNX file")
    cfg = AtrConfig(detector=args.detector, model_path=args.model, intra_op_threads=1,
                    **({} if args.threshold is None else {"score_threshold": args.threshold}))
    if args.detector == "cnn" and not model_path(cfg).is_file():
        raise ModelFileError(f"--model {args.model}: no such file, and no shipped model of that name (shipped: "
                             f"{', '.join(shipped_model_names())})")
    return cfg


def _cmd_eval(args: argparse.Namespace) -> int:
    from autonomy.atr import build_detector
    from sim.evaluation.atr_metrics import choose_threshold, ensure_heldout, evaluate_detector, threshold_sweep

    cfg = _detector_config(args)
    data = require_dataset(args.data, "--data") if args.data is not None else None
    detector = build_detector(cfg)
    data = data if data is not None else ensure_heldout()
    fan_h, fan_w = fls_fan_hw(data, "--data")
    model_hw = getattr(detector, "fan_hw", None)
    if model_hw is not None and (fan_h, fan_w) != tuple(model_hw):
        raise DatasetError(f"--data {data}: its fans are {fan_w} x {fan_h} px but the model "
                           f"{getattr(detector, 'model_path', '')} was trained on {model_hw[1]} x {model_hw[0]} px "
                           "(width x height); evaluate on fans of the sonar it was trained on, or give a model "
                           "trained on these (--model)")
    if args.sweep:
        sweep = threshold_sweep(detector, data, np.round(np.arange(0.10, 0.91, 0.025), 3),
                                max_images=args.max_images)
        best = choose_threshold(sweep)
        none_chosen = ("no threshold chosen: the detector makes no true detection at any threshold swept "
                       f"({sweep[0]['score_threshold']:.2f}-{sweep[-1]['score_threshold']:.2f})")
        if args.json:
            print(json.dumps({"data": str(data), "sweep": sweep, "chosen": best,
                              **({"note": none_chosen} if best is None else {})}))
            return 0
        print(f"eval-atr sweep {args.detector} on {data}")
        for r in sweep:
            mark = " <- chosen" if r is best else ""
            prec = NO_DETECTIONS if r["precision"] is None else f"{r['precision']:.3f}"
            print(f"  thr {r['score_threshold']:.3f}  precision {prec}  recall {r['recall']:.3f}  "
                  f"FA/frame {r['false_alarms_per_frame']:.3f}{mark}")
        if best is None:
            print(none_chosen)
        return 0
    res = evaluate_detector(detector, Path(data), cfg.score_threshold, max_images=args.max_images)
    res.update(detector=args.detector, data=str(data))
    if args.json:
        print(json.dumps(res))
        return 0
    print(f"eval-atr {res['detector']} on {res['data']} ({res['layout']} layout, {res['frames']} frames, "
          f"classes {', '.join(res['classes'])})")
    keys = ("score_threshold", "precision", "recall", "false_alarms_per_frame", "ap50", "ap50_95", "frames_per_s")
    if len(res["classes"]) > 1:
        keys = ("score_threshold", "precision", "recall", "false_alarms_per_frame", "map50", "map50_95",
                "frames_per_s")
    for k in keys:
        print(f"  {k:24s} {NO_DETECTIONS if k == 'precision' and res[k] is None else _fmt(res[k])}")
    if len(res["classes"]) > 1 or res["ap50_scored_apart"]:
        print("  AP50 by class" + (" (no ground truth: -)" if None in res["ap50_by_class"].values() else ""))
        for name, v in {**res["ap50_by_class"], **{f"{k} (scored apart)": v
                                                   for k, v in res["ap50_scored_apart"].items()}}.items():
            print(f"    {name:26s} {_fmt(v)}")
    print("  range band       gt   recall   det  precision")
    for b in res["by_range_band"]:
        lo, hi = b["range_m"]
        print(f"  {lo:5g}-{'inf' if hi is None else f'{hi:g}':>4s} m  {b['ground_truth']:5d}  {_fmt(b['recall']):>7s}"
              f"  {b['detections']:4d}  {_fmt(b['precision']):>9s}")
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("eval-atr", help="evaluate the ATR detector on a held-out set")
    p.add_argument("--data", default=None,
                   help="labelled folder: a dataset of `auvsim dataset` (annotations.json), or real frames in the "
                        "watertank layout (images/, boxes/*.xml, masks/); default: generate the held-out set")
    p.add_argument("--detector", choices=["cnn", "classical"], default="cnn")
    p.add_argument("--model", default=None,
                   help="ONNX model: a path, or the name of a shipped model (default: the shipped survey model)")
    p.add_argument("--threshold", type=probability, default=None,
                   help="operating threshold, 0 to 1 (default: the detector config's)")
    p.add_argument("--max-images", type=positive_int, default=None)
    p.add_argument("--json", action="store_true", help="print the figures as one JSON object on one line")
    p.add_argument("--sweep", action="store_true",
                   help="print precision/recall over thresholds 0.10-0.90 and the chosen operating point "
                        "(highest recall at precision >= 0.95, else best F1, among thresholds with a true "
                        "detection); use on a validation set")
    p.set_defaults(func=_cmd_eval)
