"""``auvsim train-atr``: train the ATR CNN on datasets and export ONNX (needs the ``train`` extra)."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from sim.cli.args import non_negative_int, positive_float, positive_int, size_hw, size_hw_or_none
from sim.cli.errors import CliError
from sim.dataset.errors import fls_fan_hw, require_dataset
from sim.training import TORCH_HINT
from sim.training.train import ARCH_NAMES, AUGMENTATIONS, DEFAULT_INPUT_HW, CheckpointError, TrainParams, train_atr


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
    _require_writable_folder(out, "--out")
    return out


def _require_writable_folder(path: Path, flag: str) -> None:
    """Refuse ``path`` when the nearest existing folder above it cannot be written in."""
    probe = path.parent.resolve()
    while not probe.exists():
        probe = probe.parent
    if not probe.is_dir() or not os.access(probe, os.W_OK | os.X_OK):
        raise CliError(f"{flag} {path}: cannot write in {probe}")


def _cmd_train(args: argparse.Namespace) -> int:
    try:
        import torch  # noqa: F401
    except ImportError:
        raise CliError(f"train-atr: {TORCH_HINT}") from None

    dirs = [d.strip() for d in str(args.data).split(",") if d.strip()]
    if not dirs:
        raise CliError("--data: name at least one dataset folder")
    data = [require_dataset(d, "--data") for d in dirs]
    val_dirs = [d.strip() for d in str(args.val_data).split(",") if d.strip()] if args.val_data is not None else None
    if val_dirs is not None and not val_dirs:
        raise CliError("--val-data: name at least one dataset folder")
    val = [require_dataset(d, "--val-data") for d in val_dirs] if val_dirs is not None else None
    out = _check_model_out(args.out, args.overwrite)
    if args.init_from is not None:
        if args.resume:
            raise CliError("--init-from starts a new run from another run's network; --resume continues a run: "
                           "give one")
        init = Path(args.init_from).expanduser()
        if not init.is_file():
            raise CliError(f"--init-from {init}: no such checkpoint file (a train-atr --checkpoint of the "
                           "pretraining run)")
    if args.resume and args.checkpoint is None:
        raise CliError("--resume: name the checkpoint to continue with --checkpoint FILE")
    if args.stop_after_minutes is not None and args.checkpoint is None:
        raise CliError("--stop-after-minutes: only with --checkpoint FILE (without one the run could not be resumed)")
    if args.checkpoint is not None:
        ckpt = Path(args.checkpoint).expanduser()
        if ckpt.is_dir():
            raise CliError(f"--checkpoint {ckpt}: is a folder; name the checkpoint file, e.g. {ckpt / 'atr.ckpt'}")
        if args.resume and not ckpt.is_file():
            raise CliError(f"--checkpoint {ckpt}: no such file to resume from")
        if not args.resume and ckpt.exists():
            raise CliError(f"--checkpoint {ckpt}: file exists; pass --resume to continue that run, or name a new file")
        _require_writable_folder(ckpt, "--checkpoint")
    if args.input == "native":
        fan_h, fan_w = fls_fan_hw(data[0], "--data")
        input_hw, transform = (-(-fan_h // 16) * 16, -(-fan_w // 16) * 16), "pad"
    else:
        input_hw, transform = args.input, "resize"
    params = TrainParams(input_hw=input_hw, crop_hw=args.crop, width=args.width, epochs=args.epochs,
                         batch_size=args.batch_size, lr=args.lr, max_minutes=args.max_minutes,
                         threads=args.threads, seed=args.seed, size_loss_weight=args.size_loss_weight,
                         light_heads=args.light_heads, arch=args.arch, input_transform=transform, augment=args.augment,
                         classes=tuple(c.strip() for c in args.classes.split(",")) if args.classes else None)

    try:
        summary = train_atr(data if len(data) > 1 else data[0], out, params, val_data=val,
                            checkpoint=args.checkpoint, resume=args.resume,
                            checkpoint_minutes=args.checkpoint_minutes, stop_after_minutes=args.stop_after_minutes,
                            init_from=args.init_from)
    except CheckpointError as exc:
        raise CliError(str(exc)) from None
    if not summary["finished"]:
        return 0
    check = summary["check"]
    if check["detections"] == 0:
        frames = "validation" if check["held_out"] else "training (no --val-data)"
        print(f"auvsim train-atr: warning: the model in {out} detects nothing at score threshold "
              f"{check['score_threshold']:.2f} on {check['frames']} {frames} frames holding "
              f"{check['labelled_objects']} labelled objects: it would find no target in a mission; train longer "
              "(--epochs, --max-minutes) or on more data", file=sys.stderr, flush=True)
    return 0


def _input_arg(text: str):
    """``HxW`` (:func:`size_hw`) or ``native``."""
    if str(text).lower() == "native":
        return "native"
    try:
        return size_hw(text)
    except argparse.ArgumentTypeError as exc:
        raise argparse.ArgumentTypeError(f"{exc}; or 'native' (the fan at its own resolution)") from None


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("train-atr", help="train the ATR CNN on a dataset and export ONNX (needs auvsim[train])")
    p.add_argument("--data", required=True,
                   help="dataset folder written by `auvsim dataset` (comma-separated: several, concatenated)")
    p.add_argument("--out", required=True, help="output ONNX file")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file")
    p.add_argument("--epochs", type=positive_int, default=TrainParams.epochs)
    p.add_argument("--batch-size", type=positive_int, default=TrainParams.batch_size)
    p.add_argument("--lr", type=positive_float, default=TrainParams.lr)
    p.add_argument("--width", type=positive_int, default=TrainParams.width, help="base channel width")
    p.add_argument("--input", type=_input_arg, default=DEFAULT_INPUT_HW,
                   help="model input HxW, multiples of 16, the fan resized to it (default %dx%d); or 'native': "
                        "the fan at its own resolution, zero-padded to multiples of 16" % DEFAULT_INPUT_HW)
    p.add_argument("--arch", choices=ARCH_NAMES, default=TrainParams.arch,
                   help="s4: heads at stride 4 (the v2 model); s8: stride-4 patch stem, heads at stride 8 "
                        "(for --input native)")
    p.add_argument("--checkpoint", default=None, metavar="FILE",
                   help="save the whole training state here every --checkpoint-minutes and at the end")
    p.add_argument("--resume", action="store_true",
                   help="continue the run saved in --checkpoint (same data and parameters; an existing --out "
                        "needs --overwrite)")
    p.add_argument("--checkpoint-minutes", type=positive_float, default=5.0, metavar="MIN")
    p.add_argument("--init-from", default=None, metavar="RUN.ckpt",
                   help="start from the network of another run's checkpoint (pretraining, e.g. on synthetic "
                        "frames); same --arch, --width, --light-heads and classes; a new optimiser and schedule")
    p.add_argument("--stop-after-minutes", type=positive_float, default=None, metavar="MIN",
                   help="end this session after MIN minutes (checkpoint saved, model exported as it stands); "
                        "the run goes on with --resume")
    p.add_argument("--crop", type=size_hw_or_none, default=TrainParams.crop_hw,
                   help="training crop HxW in input px, or 'none' (default 128x224)")
    p.add_argument("--max-minutes", type=positive_float, default=TrainParams.max_minutes,
                   help="training time budget over all sessions of the run; the learning rate decays over "
                        "whichever ends first, this or --epochs")
    p.add_argument("--threads", type=positive_int, default=TrainParams.threads)
    p.add_argument("--seed", type=non_negative_int, default=0)
    p.add_argument("--size-loss-weight", type=positive_float, default=TrainParams.size_loss_weight)
    p.add_argument("--light-heads", action="store_true", help="depthwise-separable heads (faster inference)")
    p.add_argument("--augment", choices=AUGMENTATIONS, default=TrainParams.augment,
                   help="basic (default): flips, gain and gamma; sonar: also a random image formation per crop (speckle, "
                        "blur, noise, contrast) for detectors trained on synthetic frames meant for real ones")
    p.add_argument("--classes", default=None,
                   help="comma-separated class names, each with labelled objects in the data (default: all in data)")
    p.add_argument("--val-data", default=None, metavar="DIR",
                   help="dataset folder(s) held out of training (comma-separated) on which the model is checked "
                        "at the end (default: the first frames of the training data)")
    p.set_defaults(func=_cmd_train)
