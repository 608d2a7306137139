"""``auvsim train-atr``: train the ATR CNN on datasets and export ONNX (needs the ``train`` extra)."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from sim.cli.args import non_negative_int, positive_float, positive_int, size_hw, size_hw_or_none
from sim.cli.errors import CliError


def _check_model_out(path: str, overwrite: bool) -> Path:
    """The ONNX file to write: not a folder, in a writable folder, not replaced unasked."""
    if not path.strip():
        raise CliError("--out: must name an ONNX file, got an empty string")
    out = Path(path).expanduser()
    if out.is_dir():
        raise CliError(f"--out {out}: is a folder; name the ONNX file to write, e.g. {out / 'atr.onnx'}")
    if out.suffix != ".onnx":
        raise CliError(f"--out {out}: the model file name must end in .onnx")
    if out.exists() and not overwrite:
        raise CliError(f"--out {out}: file exists; pass --overwrite to replace it, or name a new file")
    probe = out.parent.resolve()
    while not probe.exists():
        probe = probe.parent
    if not probe.is_dir() or not os.access(probe, os.W_OK | os.X_OK):
        raise CliError(f"--out {out}: cannot write in {probe}")
    return out


def _cmd_train(args: argparse.Namespace) -> int:
    from sim.dataset.errors import require_dataset
    from sim.training import TORCH_HINT

    try:
        import torch  # noqa: F401
    except ImportError:
        raise CliError(f"train-atr: {TORCH_HINT}") from None
    from sim.training.train import TrainParams, train_atr

    dirs = [d.strip() for d in str(args.data).split(",") if d.strip()]
    if not dirs:
        raise CliError("--data: name at least one dataset folder")
    data = [require_dataset(d, "--data") for d in dirs]
    val_dirs = [d.strip() for d in str(args.val_data).split(",") if d.strip()] if args.val_data is not None else None
    if val_dirs is not None and not val_dirs:
        raise CliError("--val-data: name at least one dataset folder")
    val = [require_dataset(d, "--val-data") for d in val_dirs] if val_dirs is not None else None
    out = _check_model_out(args.out, args.overwrite)
    params = TrainParams(input_hw=args.input, crop_hw=args.crop, width=args.width, epochs=args.epochs,
                         batch_size=args.batch_size, lr=args.lr, max_minutes=args.max_minutes,
                         threads=args.threads, seed=args.seed, size_loss_weight=args.size_loss_weight,
                         light_heads=args.light_heads,
                         classes=tuple(c.strip() for c in args.classes.split(",")) if args.classes else None)
    summary = train_atr(data if len(data) > 1 else data[0], out, params, val_data=val)
    check = summary["check"]
    if check["detections"] == 0:
        frames = "validation" if check["held_out"] else "training (no --val-data)"
        print(f"auvsim train-atr: warning: the model in {out} detects nothing at score threshold "
              f"{check['score_threshold']:.2f} on {check['frames']} {frames} frames holding "
              f"{check['labelled_objects']} labelled objects: it would find no target in a mission; train longer "
              "(--epochs, --max-minutes) or on more data", file=sys.stderr, flush=True)
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    from sim.training.train import DEFAULT_INPUT_HW, TrainParams

    p = sub.add_parser("train-atr", help="train the ATR CNN on a dataset and export ONNX (needs auvsim[train])")
    p.add_argument("--data", required=True,
                   help="dataset folder written by `auvsim dataset` (comma-separated: several, concatenated)")
    p.add_argument("--out", required=True, help="output ONNX file")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file")
    p.add_argument("--epochs", type=positive_int, default=TrainParams.epochs)
    p.add_argument("--batch-size", type=positive_int, default=TrainParams.batch_size)
    p.add_argument("--lr", type=positive_float, default=TrainParams.lr)
    p.add_argument("--width", type=positive_int, default=TrainParams.width, help="base channel width")
    p.add_argument("--input", type=size_hw, default=DEFAULT_INPUT_HW,
                   help="model input HxW, multiples of 16 (default %dx%d)" % DEFAULT_INPUT_HW)
    p.add_argument("--crop", type=size_hw_or_none, default=TrainParams.crop_hw,
                   help="training crop HxW in input px, or 'none' (default 128x224)")
    p.add_argument("--max-minutes", type=positive_float, default=TrainParams.max_minutes)
    p.add_argument("--threads", type=positive_int, default=TrainParams.threads)
    p.add_argument("--seed", type=non_negative_int, default=0)
    p.add_argument("--size-loss-weight", type=positive_float, default=TrainParams.size_loss_weight)
    p.add_argument("--light-heads", action="store_true", help="depthwise-separable heads (faster inference)")
    p.add_argument("--classes", default=None,
                   help="comma-separated class names, each with labelled objects in the data (default: all in data)")
    p.add_argument("--val-data", default=None, metavar="DIR",
                   help="dataset folder(s) held out of training (comma-separated) on which the model is checked "
                        "at the end (default: the first frames of the training data)")
    p.set_defaults(func=_cmd_train)
