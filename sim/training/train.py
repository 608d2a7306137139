"""``auvsim train-atr``: train the CenterNet-style ATR detector on a dataset and export ONNX."""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from sim.training import require_torch

DEFAULT_INPUT_HW = (240, 448)


@dataclass(frozen=True)
class TrainParams:
    """Training hyper-parameters (all recorded in the model's metadata)."""

    input_hw: tuple[int, int] = DEFAULT_INPUT_HW
    width: int = 20
    epochs: int = 30
    batch_size: int = 16
    lr: float = 3e-3
    weight_decay: float = 1e-4
    max_minutes: float = 15.0
    threads: int = 2
    seed: int = 0
    classes: tuple[str, ...] | None = None
    val_fraction: float = 0.0
    extra: dict = field(default_factory=dict)


def _focal_loss(torch, logits, target, weight):
    """CenterNet penalty-reduced focal loss (alpha 2, beta 4), normalised by object count."""
    p = torch.sigmoid(logits).clamp(1e-4, 1 - 1e-4)
    pos = (target >= 0.999).float()
    neg_w = (1 - target) ** 4
    w = weight[:, None]
    pos_loss = -(torch.log(p) * (1 - p) ** 2 * pos * w).sum()
    neg_loss = -(torch.log(1 - p) * p ** 2 * neg_w * (1 - pos) * w).sum()
    return (pos_loss + neg_loss) / pos.sum().clamp(min=1.0)


def _augment(torch, imgs, boxes_list, rng: np.random.Generator, width: int):
    """Random horizontal flip (the fan is symmetric about its centre column) and gain/gamma."""
    b = imgs.shape[0]
    flip = rng.random(b) < 0.5
    if flip.any():
        idx = torch.from_numpy(np.flatnonzero(flip))
        imgs[idx] = torch.flip(imgs[idx], dims=[-1])
    out_boxes = []
    for i, bx in enumerate(boxes_list):
        bx = bx.copy()
        if flip[i]:
            bx[:, [0, 2]] = (width - 1) - bx[:, [2, 0]]
        out_boxes.append(bx)
    gain = torch.from_numpy(rng.uniform(0.75, 1.3, size=(b, 1, 1, 1)).astype(np.float32))
    gamma = torch.from_numpy(rng.uniform(0.8, 1.25, size=(b, 1, 1, 1)).astype(np.float32))
    imgs = (imgs.clamp(0, 1) ** gamma * gain).clamp(0, 1)
    return imgs, out_boxes


def train_atr(data_dir: str | Path, out_path: str | Path, params: TrainParams = TrainParams(),
              log=print) -> dict:
    """Train on ``data_dir`` (an ``auvsim dataset`` output) and export ONNX to ``out_path``.

    Stops after ``params.epochs`` epochs or ``params.max_minutes``, whichever comes first.
    Returns a summary dict (epochs run, final losses, seconds, parameter count).
    """
    torch = require_torch()
    from sim.training.data import load_detection_arrays
    from sim.training.export import export_onnx
    from sim.training.model import STRIDE, CenterNetSmall
    from sim.training.targets import encode_targets

    torch.manual_seed(params.seed)
    torch.set_num_threads(params.threads)
    rng = np.random.default_rng(params.seed)
    t0 = time.perf_counter()
    arrays = load_detection_arrays(data_dir, params.input_hw,
                                   list(params.classes) if params.classes else None)
    n_img = arrays.images.shape[0]
    h, w = params.input_hw
    if h % 16 or w % 16:
        raise ValueError(f"input_hw {params.input_hw}: height and width must be multiples of 16")
    grid = (h // STRIDE, w // STRIDE)
    model = CenterNetSmall(len(arrays.class_names), params.width)
    n_params = sum(p.numel() for p in model.parameters())
    opt = torch.optim.AdamW(model.parameters(), lr=params.lr, weight_decay=params.weight_decay)
    steps_per_epoch = max(1, int(np.ceil(n_img / params.batch_size)))
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=params.lr, total_steps=params.epochs * steps_per_epoch,
                                                pct_start=0.15)
    log(f"train-atr: {n_img} images, classes {arrays.class_names}, {n_params} parameters, "
        f"input {h}x{w}, load {time.perf_counter() - t0:.1f} s")
    deadline = t0 + 60.0 * params.max_minutes
    model.train()
    history = []
    epoch = 0
    stopped_early = False
    for epoch in range(1, params.epochs + 1):
        order = rng.permutation(n_img)
        sums = np.zeros(3)
        for s in range(steps_per_epoch):
            idx = order[s * params.batch_size:(s + 1) * params.batch_size]
            if idx.size == 0:
                continue
            imgs = torch.from_numpy(arrays.images[idx].astype(np.float32) / 255.0)[:, None]
            imgs, boxes = _augment(torch, imgs, [arrays.boxes[i] for i in idx], rng, w)
            tg = [encode_targets(boxes[k], arrays.class_ids[i], arrays.ignore[i], len(arrays.class_names),
                                 grid, STRIDE) for k, i in enumerate(idx)]
            heat_t = torch.from_numpy(np.stack([t.heat for t in tg]))
            weight_t = torch.from_numpy(np.stack([t.weight for t in tg]))
            size_t = torch.from_numpy(np.stack([t.size_log for t in tg]))
            off_t = torch.from_numpy(np.stack([t.offset for t in tg]))
            reg_t = torch.from_numpy(np.stack([t.reg_mask for t in tg]))[:, None]
            logits, size_log, offset = model(imgs)
            l_heat = _focal_loss(torch, logits, heat_t, weight_t)
            n_reg = reg_t.sum().clamp(min=1.0)
            l_size = (torch.abs(size_log - size_t) * reg_t).sum() / n_reg
            l_off = (torch.abs(offset - off_t) * reg_t).sum() / n_reg
            loss = l_heat + 0.5 * l_size + l_off
            opt.zero_grad()
            loss.backward()
            opt.step()
            sched.step()
            sums += [l_heat.item(), l_size.item(), l_off.item()]
            if time.perf_counter() > deadline:
                stopped_early = True
                break
        mean = sums / steps_per_epoch
        history.append({"epoch": epoch, "heat": mean[0], "size": mean[1], "offset": mean[2]})
        log(f"epoch {epoch}: heat {mean[0]:.3f} size {mean[1]:.3f} offset {mean[2]:.3f} "
            f"({time.perf_counter() - t0:.0f} s)")
        if stopped_early:
            log(f"train-atr: time budget of {params.max_minutes} min reached")
            break
    model.eval()
    manifest_path = Path(data_dir) / "manifest.json"
    data_manifest = json.loads(manifest_path.read_text()) if manifest_path.is_file() else {}
    meta = {"train_params": json.dumps({k: v for k, v in asdict(params).items()}, default=list),
            "train_data": json.dumps({"dir": str(data_dir), "n_images": n_img,
                                      "generator_version": data_manifest.get("generator_version"),
                                      "seed": data_manifest.get("seed")}),
            "epochs_run": str(epoch)}
    export_onnx(model, out_path, params.input_hw, arrays.fan_hw, arrays.class_names, meta)
    summary = {"epochs_run": epoch, "seconds": time.perf_counter() - t0, "parameters": n_params,
               "images": n_img, "classes": arrays.class_names, "history": history,
               "out": str(out_path), "stopped_on_time": stopped_early}
    log(f"train-atr: wrote {out_path} after {summary['seconds']:.0f} s")
    return summary


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``train-atr`` on an argparse ``subparsers`` object."""
    p = subparsers.add_parser("train-atr", help="train the ATR CNN on a dataset and export ONNX")
    p.add_argument("--data", required=True, help="dataset directory written by `auvsim dataset`")
    p.add_argument("--out", required=True, help="output ONNX file")
    p.add_argument("--epochs", type=int, default=TrainParams.epochs)
    p.add_argument("--batch-size", type=int, default=TrainParams.batch_size)
    p.add_argument("--lr", type=float, default=TrainParams.lr)
    p.add_argument("--width", type=int, default=TrainParams.width, help="base channel width")
    p.add_argument("--input", default=f"{DEFAULT_INPUT_HW[0]}x{DEFAULT_INPUT_HW[1]}",
                   help="model input HxW, multiples of 16 (default %(default)s)")
    p.add_argument("--max-minutes", type=float, default=TrainParams.max_minutes)
    p.add_argument("--threads", type=int, default=TrainParams.threads)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--classes", default=None, help="comma-separated class names (default: all in data)")
    p.set_defaults(func=train_main)
    return p


def train_main(args: argparse.Namespace) -> int:
    """Entry point for ``auvsim train-atr``."""
    try:
        hh, ww = (int(v) for v in str(args.input).lower().split("x"))
    except ValueError:
        raise SystemExit(f"train-atr: --input must look like 240x448, got {args.input!r}")
    params = TrainParams(input_hw=(hh, ww), width=args.width, epochs=args.epochs, batch_size=args.batch_size,
                         lr=args.lr, max_minutes=args.max_minutes, threads=args.threads, seed=args.seed,
                         classes=tuple(args.classes.split(",")) if args.classes else None)
    train_atr(args.data, args.out, params)
    return 0
