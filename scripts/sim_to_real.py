"""The sim-to-real study: a detector trained on synthetic frames only, on a few or most real
frames, and pretrained on synthetic then fine-tuned on real, each scored on real frames it
never saw (pycocotools AP50 per class, mean AP50, AP50:95).

Steps, each skipped when its output is already there (rerun the same command to resume; a
stopped training resumes from its checkpoint):

1. ``OUT/synthetic``: ``--synthetic-frames`` frames of the dataset spec ``--spec`` (default
   ``marine_debris_watertank``), and ``OUT/synthetic_val`` (a tenth as many, another seed);
2. ``OUT/split_few``, ``OUT/split_most`` (and ``_s1``, ``_s2``... with ``--splits``): the real
   folder split into ``--few`` and ``--most`` training frames and the rest (links,
   ``sim.dataset.split``; by whole scenes unless ``--split-by frame``);
3. trainings (``auvsim train-atr``, stride-8 native-resolution CenterNet, one thread):
   ``synthetic``, ``real_few``, ``real_most``, ``synthetic+real_few``, ``synthetic+real_most``
   (the last two start from ``synthetic``'s network, ``--init-from``);
4. scores: every model on the real frames outside its training part (the synthetic-only one
   on all of them and on each split's rest, so it is compared on the same frames);
5. ``OUT/sim_to_real.json``, ``OUT/sim_to_real.md`` (the table, training CPU time, and what
   the synthetic-only detector called each real object), ``OUT/sim_to_real_pr.png`` (the
   precision-recall curves) and ``OUT/real_frames_synthetic_only.png`` (real frames with the
   synthetic-only detector's boxes and the true ones).

Usage::

    python scripts/sim_to_real.py --real ../shared/data/marine-debris-watertank-dev --out runs/s2r \\
        [--synthetic-frames 8000] [--epochs 30] [--finetune-steps 2400] [--splits 3] [--split-by scene] [--workers 2]

The real folder is an argument and is never copied. ``--smoke`` runs every step on a few
frames and one epoch (minutes; a check of the plumbing, not of accuracy).
"""

from __future__ import annotations

import argparse
import json
import re
import resource
import sys
import time
from pathlib import Path

import cv2
import numpy as np

from sim.cli import main as auvsim
from sim.dataset.errors import DatasetError
from sim.dataset.generate import generate_dataset, generation_args
from sim.dataset.labelled_folder import LabelledFolder, load_labelled_folder
from sim.dataset.spec import load_spec
from sim.dataset.split import split_folder
from sim.training.train import AUGMENTATIONS

MODELS = ("synthetic", "real_few", "real_most", "synthetic+real_few", "synthetic+real_most")


def _cpu_s() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN), resource.getrusage(resource.RUSAGE_SELF)
    return sum(x.ru_utime + x.ru_stime for x in r)


def _train(name: str, data: list[Path], val: Path, out: Path, args, init: Path | None, epochs: int,
           augment: str = "basic") -> dict:
    """Train (or resume, or skip when done) one model; its record: ONNX, checkpoint, CPU s."""
    onnx, ckpt, done = out / f"{name}.onnx", out / f"{name}.ckpt", out / f"{name}.done.json"
    if done.is_file():
        rec = json.loads(done.read_text())
        if (rec.get("epochs") == epochs and rec.get("init_from") == (None if init is None else str(init))
                and rec.get("augment", "basic") == augment):
            return rec
        print(f"sim_to_real: {name} was trained with other settings ({rec.get('epochs')} epochs); training again",
              flush=True)
        for f in (onnx, ckpt, done):
            f.unlink(missing_ok=True)
    argv = ["train-atr", "--data", ",".join(str(d) for d in data), "--val-data", str(val), "--out", str(onnx),
            "--overwrite", "--arch", "s8", "--input", "native", "--crop", args.crop, "--width", str(args.width),
            "--light-heads", "--epochs", str(epochs), "--batch-size", str(args.batch_size), "--lr", str(args.lr),
            "--max-minutes", "100000", "--threads", "1", "--seed", str(args.seed), "--checkpoint", str(ckpt),
            "--checkpoint-minutes", "5", "--augment", augment]
    if ckpt.is_file():
        argv.append("--resume")
    elif init is not None:
        argv += ["--init-from", str(init)]
    t0 = _cpu_s()
    code = auvsim(argv)
    if code != 0:
        raise SystemExit(f"sim_to_real: training {name} failed (exit {code})")
    rec = {"onnx": str(onnx), "checkpoint": str(ckpt), "cpu_s": _cpu_s() - t0, "epochs": epochs,
           "data": [str(d) for d in data], "init_from": None if init is None else str(init), "augment": augment}
    done.write_text(json.dumps(rec, indent=1))
    return rec


def _score(model: Path, data: Path) -> dict:
    from autonomy.atr.cnn_detector import CnnDetector
    from sim.evaluation.atr_metrics import evaluate_detector

    det = CnnDetector(model, score_threshold=0.3)
    r = evaluate_detector(det, data, 0.3, pr_curves=True)
    return {k: r.get(k) for k in ("frames", "map50", "map50_95", "ap50_by_class", "ap50_scored_apart", "precision",
                                  "recall", "ground_truth", "pr50_by_class")}


def _confusion(model: Path, folder: LabelledFolder, iou_min: float = 0.5, score_min: float = 0.3) -> dict:
    """What the detector called each labelled object of ``data``: per true class, the counts
    of the class of the highest-scoring detection overlapping it (IoU >= ``iou_min``, any
    class, score >= ``score_min``), or ``missed``; and the detections overlapping no object
    (``false``) by detected class. Separates "found but named wrong" from "not found"."""
    from autonomy.atr.cnn_detector import CnnDetector
    from autonomy.atr.nms import box_iou
    from sim.evaluation.atr_metrics import frame_from_record

    det = CnnDetector(model, score_threshold=score_min)
    cats = {c["id"]: c["name"] for c in folder.coco["categories"]}
    by_image: dict[int, list[dict]] = {}
    for a in folder.coco["annotations"]:
        by_image.setdefault(a["image_id"], []).append(a)
    table: dict[str, dict[str, int]] = {}
    false: dict[str, int] = {}
    for rec in folder.coco["images"]:
        dets = det.detect(frame_from_record(rec, folder.image(rec)))
        boxes = np.array([d.box_xyxy_px for d in dets], dtype=float).reshape(-1, 4)
        gts = by_image.get(rec["id"], [])
        g = np.array([[a["bbox"][0], a["bbox"][1], a["bbox"][0] + a["bbox"][2], a["bbox"][1] + a["bbox"][3]]
                      for a in gts], dtype=float).reshape(-1, 4)
        iou = box_iou(boxes, g)
        for j, a in enumerate(gts):
            row = table.setdefault(cats[a["category_id"]], {})
            hits = np.flatnonzero(iou[:, j] >= iou_min) if len(dets) else np.array([], int)
            name = "missed" if hits.size == 0 else dets[int(hits[np.argmax([dets[i].score for i in hits])])].class_name
            row[name] = row.get(name, 0) + 1
        for i, d in enumerate(dets):
            if not len(gts) or iou[i].max() < iou_min:
                false[d.class_name] = false.get(d.class_name, 0) + 1
    return {"iou_min": iou_min, "score_min": score_min, "by_true_class": table, "false_by_detected_class": false}


def _pr_png(results: dict, out: Path) -> None:
    """Each model's precision-recall curve at IoU 0.5 (COCOeval's, the mean over the classes
    with objects of its per-class curves; past a class's largest recall its precision is 0),
    on the frames it was scored on, split 0: one panel per scoring set."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    sets = []
    for row in results["rows"]:
        if row.get("split") in (None, 0) and row["score"].get("pr50_by_class"):
            sets.append(row)
    panels = sorted({r["on"] for r in sets}, key=lambda x: (x != "all real frames", x))
    fig = Figure(figsize=(4.2 * max(len(panels), 1), 3.8))
    FigureCanvasAgg(fig)
    if not panels:  # no model detected anything: say so rather than draw empty axes
        fig.text(0.5, 0.5, "no model made a detection on the real frames", ha="center", va="center")
    recall = np.linspace(0.0, 1.0, 101)
    for k, on in enumerate(panels):
        ax = fig.add_subplot(1, len(panels), k + 1)
        for row in (r for r in sets if r["on"] == on):
            curves = [np.clip(np.array(c, dtype=float), 0.0, None) for c in row["score"]["pr50_by_class"].values()
                      if c is not None]
            if curves:
                ax.plot(recall, np.mean(curves, axis=0), label=f"{row['model']} ({row['score']['map50']:.2f})")
        ax.set_xlabel("recall (IoU 0.5)")
        ax.set_ylabel("precision, mean over classes")
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1.02)
        ax.set_title(f"scored on {on}", fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, title="model (mean AP50)", title_fontsize=7)
    fig.tight_layout()
    fig.savefig(str(out), dpi=110)


def _page(model: Path, folder: LabelledFolder, out: Path, n: int = 8) -> None:
    """Real frames with the model's boxes (green) and the true ones (thin white)."""
    from autonomy.atr.cnn_detector import CnnDetector
    from sim.evaluation.atr_metrics import frame_from_record

    det = CnnDetector(model, score_threshold=0.3)
    tiles = []
    step = max(1, len(folder.coco["images"]) // n)
    for rec in folder.coco["images"][::step][:n]:
        img = folder.image(rec)
        page = cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)
        for a in folder.coco["annotations"]:
            if a["image_id"] == rec["id"]:
                x, y, w, h = (int(round(v)) for v in a["bbox"])
                cv2.rectangle(page, (x, y), (x + w - 1, y + h - 1), (255, 255, 255), 1)
        for d in det.detect(frame_from_record(rec, img)):
            x0, y0, x1, y1 = (int(round(v)) for v in d.box_xyxy_px)
            cv2.rectangle(page, (x0, y0), (x1, y1), (80, 220, 80), 1)
            cv2.putText(page, f"{d.class_name} {d.score:.2f}", (x0, max(y0 - 3, 9)), cv2.FONT_HERSHEY_SIMPLEX, 0.33,
                        (80, 220, 80), 1, cv2.LINE_AA)
        tiles.append(page)
    cols = 4
    h, w = tiles[0].shape[:2]
    grid = np.zeros((-(-len(tiles) // cols) * h, min(cols, len(tiles)) * w, 3), np.uint8)
    for k, t in enumerate(tiles):
        grid[(k // cols) * h:(k // cols + 1) * h, (k % cols) * w:(k % cols + 1) * w] = t
    cv2.imwrite(str(out), grid, [cv2.IMWRITE_PNG_COMPRESSION, 9])


def _table(results: dict, train: dict) -> str:
    """Markdown: one row per model and scoring set (and split), then, with several splits, the
    mean and standard deviation of mean AP50 over the splits."""
    lines = ["| model | scored on | split | frames | mean AP50 | AP50:95 | " + " | ".join(
        results["classes"]) + " | Wall (apart) | training CPU h |",
             "|---|---|---|---|---|---|" + "---|" * len(results["classes"]) + "---|---|"]
    for row in results["rows"]:
        s = row["score"]
        per = " | ".join("-" if s["ap50_by_class"].get(c) is None else f"{s['ap50_by_class'][c]:.2f}"
                         for c in results["classes"])
        wall = s["ap50_scored_apart"].get("Wall")
        m = row["model"]  # a fine-tuned model's time includes its pretraining's
        cpu = train[m]["cpu_s"] + (train["synthetic"]["cpu_s"] if m.startswith("synthetic+") else 0.0)
        split = "-" if row.get("split") is None else str(row["split"])
        lines.append(f"| {row['model']} | {row['on']} | {split} | {s['frames']} | {s['map50']:.3f} | "
                     f"{s['map50_95']:.3f} | {per} | {'-' if wall is None else f'{wall:.2f}'} | {cpu / 3600:.2f} |")
    if results.get("splits", 1) > 1:
        lines += ["", f"Mean over {results['splits']} splits (mean AP50, mean +- sd):", "",
                  "| model | scored on | mean AP50 | AP50:95 |", "|---|---|---|---|"]
        groups: dict[tuple[str, str], list[dict]] = {}
        for row in results["rows"]:
            if row.get("split") is not None:
                base = re.sub(r"_s\d+$", "", row["model"])
                groups.setdefault((base, row["on"]), []).append(row["score"])
        for (m, on), scores in groups.items():
            a = np.array([s["map50"] for s in scores])
            b = np.array([s["map50_95"] for s in scores])
            lines.append(f"| {m} | {on} | {a.mean():.3f} +- {a.std(ddof=1) if len(a) > 1 else 0:.3f} | "
                         f"{b.mean():.3f} |")
    return "\n".join(lines)


def _confusion_table(conf: dict, classes: list[str]) -> str:
    """Markdown: rows true classes, columns what the synthetic-only detector called them."""
    cols = classes + ["Wall", "missed"]
    lines = [f"Synthetic-only detector on all real frames: what each labelled object was called (the "
             f"highest-scoring detection with IoU >= {conf['iou_min']}, score >= {conf['score_min']}):", "",
             "| true \\ called | " + " | ".join(cols) + " | found, any name | found and named right |",
             "|---|" + "---|" * (len(cols) + 2)]
    for c in classes + ["Wall"]:
        row = conf["by_true_class"].get(c, {})
        n = sum(row.values())
        right = row.get(c, 0) / n if n else float("nan")
        found = (n - row.get("missed", 0)) / n if n else float("nan")
        lines.append(f"| {c} | " + " | ".join(str(row.get(k, 0)) for k in cols) + f" | {found:.2f} | {right:.2f} |")
    fa = conf["false_by_detected_class"]
    lines.append("")
    lines.append("Detections on no labelled object: " + (", ".join(f"{k} {v}" for k, v in sorted(fa.items()))
                                                         or "none") + ".")
    return "\n".join(lines)


def run(args) -> dict:
    out = Path(args.out)
    real = Path(args.real)
    real_folder = load_labelled_folder(real, "--real")  # refuses a folder that is not labelled frames, before any work
    n_real = len(real_folder.coco["images"])
    if not args.most < n_real:
        raise ValueError(f"--most {args.most}: must be below the {n_real} frames of --real {real} (the rest are "
                         "scored)")
    spec = load_spec(args.spec)
    out.mkdir(parents=True, exist_ok=True)
    syn, syn_val = out / "synthetic", out / "synthetic_val"
    t = time.perf_counter()
    for folder, n, seed in ((syn, args.synthetic_frames, args.seed), (syn_val, max(args.synthetic_frames // 10, 4),
                                                                      args.seed + 1000)):
        if not (folder / "annotations.json").is_file() or not json.loads(
                (folder / "manifest.json").read_text()).get("complete"):
            print(f"sim_to_real: synthetic frames -> {folder}", flush=True)
            generate_dataset(folder, n, seed=seed, workers=args.workers, progress=not args.quiet,
                             **generation_args(spec))
    train: dict[str, dict] = {}
    train["synthetic"] = _train("synthetic", [syn], syn_val, out, args, None, args.epochs, args.augment)
    rows = [{"model": "synthetic", "on": "all real frames", "split": None,
             "score": _score(Path(train["synthetic"]["onnx"]), real)}]
    for k in range(args.splits):
        tag = "" if k == 0 else f"_s{k}"
        for name, n in (("few", args.few), ("most", args.most)):
            d = out / f"split_{name}{tag}"
            if not (d / "split.json").is_file():
                split_folder(real, n, args.seed + k, d, by=args.split_by)
            elif (made_by := json.loads((d / "split.json").read_text()).get("by", "frame")) != args.split_by:
                raise ValueError(f"--split-by {args.split_by}: {out} holds splits made by {made_by}; use a new --out")
            tr, rest = d / "train", d / "rest"
            # every real-frame run gets the same optimiser steps, whatever its frame count
            epochs = max(1, -(-args.finetune_steps // -(-n // args.batch_size)))  # train.py: ceil(n / batch) a step
            train[f"real_{name}{tag}"] = _train(f"real_{name}{tag}", [tr], rest, out, args, None, epochs)
            train[f"synthetic+real_{name}{tag}"] = _train(f"synthetic+real_{name}{tag}", [tr], rest, out, args,
                                                          Path(train["synthetic"]["checkpoint"]), epochs)
            for m in ("synthetic", f"real_{name}{tag}", f"synthetic+real_{name}{tag}"):
                rows.append({"model": m, "on": f"the {name} split's rest", "split": k,
                             "score": _score(Path(train[m]["onnx"]), rest)})
    classes = list(real_folder.target_classes)
    results = {"real": str(real.resolve()), "spec": spec.name, "synthetic_frames": args.synthetic_frames,
               "few": args.few, "most": args.most, "seed": args.seed, "splits": args.splits,
               "finetune_steps": args.finetune_steps, "augment": args.augment, "split_by": args.split_by, "smoke": bool(args.smoke),
               "classes": classes, "rows": rows, "training": train, "wall_s": time.perf_counter() - t,
               "confusion_synthetic_only": _confusion(Path(train["synthetic"]["onnx"]), real_folder)}
    (out / "sim_to_real.json").write_text(json.dumps(results, indent=1))
    smoke = ("**Smoke run** (`--smoke`: a check of the plumbing on a few frames and one epoch or step each; "
             "not a measurement)\n\n") if args.smoke else ""
    (out / "sim_to_real.md").write_text(smoke + _table(results, train) + "\n\n"
                                        + _confusion_table(results["confusion_synthetic_only"], classes) + "\n")
    _pr_png(results, out / "sim_to_real_pr.png")
    _page(Path(train["synthetic"]["onnx"]), real_folder, out / "real_frames_synthetic_only.png")
    return results


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description="The sim-to-real study: a detector trained on synthetic frames only, "
                                 "on a few or most real frames, and pretrained on synthetic then fine-tuned on real, "
                                 "each scored on real frames it never saw (docs/studies/sim_to_real.md).")
    ap.add_argument("--real", required=True, help="real labelled frames (watertank layout)")
    ap.add_argument("--out", required=True, help="study folder (rerun the same command to resume)")
    ap.add_argument("--spec", default="marine_debris_watertank", help="dataset spec of the synthetic frames")
    ap.add_argument("--synthetic-frames", type=int, default=8000, help="synthetic training frames (default 8000)")
    ap.add_argument("--few", type=int, default=60, help="real training frames, few (10 %% of 600)")
    ap.add_argument("--most", type=int, default=480, help="real training frames, most (80 %% of 600)")
    ap.add_argument("--epochs", type=int, default=30, help="epochs on the synthetic frames (default 30)")
    ap.add_argument("--finetune-steps", type=int, default=2400,
                    help="optimiser steps of every real-frame run, alone or fine-tuning (epochs follow from the "
                         "frame count, so --few and --most runs train equally long; default 2400: at 600, 480 real "
                         "frames alone were far from trained)")
    ap.add_argument("--splits", type=int, default=1,
                    help="random splits of the real frames (seeds --seed, --seed+1, ...); the table gives each "
                         "and their mean")
    ap.add_argument("--split-by", choices=("scene", "frame"), default="scene",
                    help="scene (default): whole scenes go to training or to scoring, so no model is scored on "
                         "near-copies of its training frames (sim/dataset/split.py); frame: a random draw of frames")
    ap.add_argument("--width", type=int, default=24, help="detector base channel width (default 24)")
    ap.add_argument("--batch-size", type=int, default=16, help="training batch size (default 16)")
    ap.add_argument("--lr", type=float, default=0.004, help="learning rate (default 0.004)")
    ap.add_argument("--crop", default="224x224", help="training crop HxW (multiples of 16) or none")
    ap.add_argument("--augment", choices=AUGMENTATIONS, default="basic",
                    help="augmentation of the synthetic-only training (train-atr --augment): sonar adds a random "
                         "image formation per crop; the real-frame runs use basic")
    ap.add_argument("--seed", type=int, default=0,
                    help="root seed: synthetic frames, splits, training (default 0)")
    ap.add_argument("--workers", type=int, default=1, help="dataset worker processes")
    ap.add_argument("--smoke", action="store_true", help="every step on a few frames, one epoch (a plumbing check)")
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args(argv)
    bad = next((f"--{k.replace('_', '-')} {v}: must be >= 1" for k, v in vars(args).items()
                if k in ("synthetic_frames", "few", "most", "epochs", "finetune_steps", "splits", "width", "batch_size",
                         "workers") and v < 1), None)
    if bad is None and not args.few < args.most:
        bad = f"--few {args.few}: must be below --most {args.most}"
    if bad is None and not args.lr > 0:
        bad = f"--lr {args.lr}: must be > 0"
    if bad:
        print(f"sim_to_real: {bad}", file=sys.stderr)
        return 2
    if args.smoke:  # the user's values are checked above, then replaced by tiny ones
        args.synthetic_frames, args.epochs, args.finetune_steps, args.width, args.batch_size = 8, 1, 1, 4, 4
        args.few, args.most = min(args.few, 2), min(args.most, 4)
        if not args.quiet:
            print("sim_to_real: --smoke: 8 synthetic frames, 2 and 4 real training frames, one epoch or step each, "
                  "width 4 (a check of the plumbing, not a measurement)", flush=True)
    try:
        res = run(args)
    except (DatasetError, ValueError) as exc:
        print(f"sim_to_real: {exc}", file=sys.stderr)
        return 2
    print((Path(args.out) / "sim_to_real.md").read_text(), end="")
    print(f"sim_to_real: wrote {args.out}/sim_to_real.json, sim_to_real.md, sim_to_real_pr.png, "
          f"real_frames_synthetic_only.png ({res['wall_s'] / 60:.1f} min)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
