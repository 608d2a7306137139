"""Detector evaluation on a labelled FLS dataset (``auvsim eval-atr``, ``auvsim bench atr``).

Figures, for the target classes (``opi`` by default):
- precision, recall, false alarms per frame at the operating threshold (greedy matching by
  score at IoU >= ``DETECTION_MATCH_IOU`` (0.5); detections on ``iscrowd`` (barely visible) objects are ignored);
  precision is None (JSON null) where there is no detection: undefined, not 1;
- AP50 and AP50:95 from ``pycocotools`` COCOeval (the COCO reference implementation);
- the same precision/recall split by range band (ground truth by its true range,
  detections by their reference-point range);
- ``frames_per_s``: detector wall time per frame on one core (onnxruntime intra-op threads 1).
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import time
from pathlib import Path
from typing import Sequence

import cv2
import numpy as np

from autonomy.messages import FlsFrame
from autonomy.sonar_geometry import FanGeometry
from sim.dataset.coco_io import ANNOTATIONS_FILE, coco_bbox_to_xyxy, xyxy_to_coco_bbox
from sim.dataset.labelled_folder import SCORED_APART, load_labelled_folder
from sim.dataset.errors import DatasetError
from sim.evaluation.detection_matching import match_frame
from autonomy.atr.cnn_detector import CnnDetector

DEFAULT_RANGE_BANDS_M = (0.0, 10.0, 20.0, 30.0, math.inf)


def frame_from_record(image_rec: dict, fan: np.ndarray) -> FlsFrame:
    """Rebuild the :class:`FlsFrame` of a dataset image (geometry stored in its record)."""
    g = image_rec["fan_geometry"]
    geom = FanGeometry(int(g["width_px"]), int(g["height_px"]), float(g["range_min_m"]), float(g["range_max_m"]),
                       float(g["fov_rad"]), float(g["m_per_px"]), float(g["apex_x_px"]), float(g["apex_y_px"]))
    return FlsFrame(t_s=float(image_rec.get("t_s", 0.0)), polar=np.zeros((0, 0), np.uint8), fan=fan, geometry=geom,
                    mount_pos_body_m=np.zeros(3), mount_rpy_rad=np.zeros(3))


def _pr(tp: int, fp: int, n_gt: int) -> tuple[float | None, float | None]:
    """Precision and recall; None where undefined (precision without any detection, recall
    without any ground truth), not 1."""
    precision = tp / (tp + fp) if tp + fp else None
    recall = tp / n_gt if n_gt else None
    return precision, recall


def evaluate_detector(detector, data_dir: str | Path, score_threshold: float,
                      target_classes: Sequence[str] | None = None, min_score: float = 0.05,
                      range_bands_m: Sequence[float] | None = None,
                      max_images: int | None = None, coco_ap: bool = True, pr_curves: bool = False) -> dict:
    """Evaluate ``detector`` (``.detect(frame, score_threshold=...)``) on a labelled folder of
    either layout (:mod:`sim.dataset.labelled_folder`: a dataset of ``auvsim dataset``, or
    the watertank layout of real frames).

    Detections down to ``min_score`` feed COCOeval (pycocotools, [COCO]): ``map50`` and
    ``map50_95`` are the mean over ``target_classes`` (default: the folder's, ``opi`` for the
    project's datasets, every class but the wall for the watertank layout) of each class's
    AP at IoU 0.5 and averaged over IoU 0.5:0.95, ``ap50_by_class`` each class's, and
    ``ap50_scored_apart`` the wall's where the folder has one (``ap50``, ``ap50_95``: the
    same means, the names of the single-class report). The operating point (precision,
    recall, false alarms, range bands) uses ``score_threshold`` over the target classes.
    ``pr_curves``: also ``pr50_by_class``, each class's COCOeval precision at IoU 0.5 at the
    101 recall points 0, 0.01 .. 1 (0 past the largest recall reached; None for a class without
    ground truth).

    Returns a JSON-serialisable dict (AP figures NaN if not ``coco_ap``); ``precision`` is
    None when the detector made no detection at ``score_threshold`` (undefined: no detection
    is neither right nor wrong), as a band's precision without detections.

    Raises:
        DatasetError: the folder is not a labelled folder, lacks a target class, holds no image
            or no labelled target in the frames evaluated, an image cannot be read, or the
            detector names none of the target classes.
    """
    from pycocotools.coco import COCO

    folder = load_labelled_folder(data_dir, "--data")
    data_dir = folder.root
    if max_images is not None and max_images < 1:
        raise DatasetError(f"--max-images: must be >= 1, got {max_images}")
    with contextlib.redirect_stdout(io.StringIO()):
        coco_gt = COCO()
        coco_gt.dataset = folder.coco
        coco_gt.createIndex()
    name_to_cat = {c["name"]: c["id"] for c in coco_gt.loadCats(coco_gt.getCatIds())}
    target_classes = tuple(folder.target_classes if target_classes is None else target_classes)
    missing = [c for c in target_classes if c not in name_to_cat]
    if missing:
        raise DatasetError(f"--data {data_dir}: classes {missing} not in its labels (it has {sorted(name_to_cat)})")
    det_classes = getattr(detector, "class_names", None)
    if det_classes is not None and not set(det_classes) & set(target_classes):
        raise DatasetError(f"--data {data_dir}: the detector's classes ({', '.join(det_classes)}) are none of the "
                           f"data's ({', '.join(target_classes)}); give a CNN trained on these classes "
                           "(--detector cnn --model FILE.onnx)")
    target_cats = [name_to_cat[c] for c in target_classes]
    apart_cats = [name_to_cat[c] for c in SCORED_APART if c in name_to_cat and c not in target_classes]
    img_ids = sorted(coco_gt.getImgIds())[:max_images]
    if not img_ids:
        raise DatasetError(f"--data {data_dir}: the dataset holds no images")
    gt_ids = coco_gt.getAnnIds(imgIds=img_ids, catIds=target_cats, iscrowd=False)
    if not gt_ids:
        raise DatasetError(f"--data {data_dir}: the {len(img_ids)} frames evaluated hold no labelled "
                           f"{'/'.join(target_classes)} object, so recall and AP are undefined; use a larger set")
    bands = list(range_bands_m if range_bands_m is not None else range_bands_for(folder.coco["images"]))
    n_bands = len(bands) - 1
    tp = fp = n_gt = 0
    band_tp_gt = np.zeros(n_bands, int)
    band_gt = np.zeros(n_bands, int)
    band_tp_det = np.zeros(n_bands, int)
    band_fp = np.zeros(n_bands, int)
    coco_dets = []
    infer_s = 0.0
    for img_id in img_ids:
        rec = coco_gt.loadImgs(img_id)[0]
        frame = frame_from_record(rec, folder.image(rec))
        t0 = time.perf_counter()
        dets = detector.detect(frame, score_threshold=min_score)
        infer_s += time.perf_counter() - t0
        anns = [a for a in coco_gt.loadAnns(coco_gt.getAnnIds(imgIds=img_id)) if a["category_id"] in target_cats]
        for d in dets:
            if d.class_name in name_to_cat:
                x, y, w, h = xyxy_to_coco_bbox(d.box_xyxy_px[None])[0]
                coco_dets.append({"image_id": img_id, "category_id": name_to_cat[d.class_name],
                                  "bbox": [float(x), float(y), float(w), float(h)], "score": d.score})
        for cat in target_cats:
            cat_name = coco_gt.loadCats(cat)[0]["name"]
            ops = [d for d in dets if d.class_name == cat_name and d.score >= score_threshold]
            gts = [a for a in anns if a["category_id"] == cat]
            det_boxes = np.array([d.box_xyxy_px for d in ops], dtype=float).reshape(-1, 4)
            det_scores = np.array([d.score for d in ops], dtype=float)
            det_range = np.array([d.range_m for d in ops], dtype=float)
            gt_boxes = coco_bbox_to_xyxy(np.array([a["bbox"] for a in gts], dtype=float).reshape(-1, 4))
            gt_crowd = np.array([bool(a.get("iscrowd", 0)) for a in gts], dtype=bool)
            gt_range = np.array([a["attributes"]["range_m"] for a in gts], dtype=float)
            state, matched = match_frame(det_boxes, det_scores, gt_boxes, gt_crowd)
            tp += int((state == 1).sum())
            fp += int((state == 0).sum())
            n_gt += int((~gt_crowd).sum())
            gb = np.digitize(gt_range, bands) - 1
            db = np.digitize(det_range, bands) - 1
            for b in range(n_bands):
                band_gt[b] += int(((gb == b) & ~gt_crowd).sum())
                band_tp_gt[b] += int(((gb == b) & matched).sum())
                band_tp_det[b] += int(((db == b) & (state == 1)).sum())
                band_fp[b] += int(((db == b) & (state == 0)).sum())
    n_img = len(img_ids)
    ap50 = ap = float("nan")
    by_class: dict[str, float | None] = {c: (float("nan") if not coco_ap else None) for c in target_classes}
    apart: dict[str, float | None] = {}
    if coco_dets and coco_ap:
        ap, per_cat, curves = _coco_ap(coco_gt, coco_dets, img_ids, target_cats + apart_cats, len(target_cats))
        by_class = {c: per_cat[name_to_cat[c]] for c in target_classes}
        apart = {coco_gt.loadCats(c)[0]["name"]: per_cat[c] for c in apart_cats}
        present = [v for v in by_class.values() if v is not None]
        ap50 = float(np.mean(present)) if present else 0.0  # the targets' mean (not the wall's)
    elif n_gt and coco_ap:
        ap = ap50 = 0.0
        by_class = {c: (0.0 if coco_gt.getAnnIds(imgIds=img_ids, catIds=[name_to_cat[c]]) else None)
                    for c in target_classes}
        apart = {coco_gt.loadCats(c)[0]["name"]: (0.0 if coco_gt.getAnnIds(imgIds=img_ids, catIds=[c]) else None)
                 for c in apart_cats}
    precision, recall = _pr(tp, fp, n_gt)
    by_band = []
    for b in range(n_bands):
        p_b = band_tp_det[b] / (band_tp_det[b] + band_fp[b]) if band_tp_det[b] + band_fp[b] else None
        r_b = band_tp_gt[b] / band_gt[b] if band_gt[b] else None
        by_band.append({"range_m": [bands[b], bands[b + 1] if math.isfinite(bands[b + 1]) else None],
                        "ground_truth": int(band_gt[b]), "recall": r_b,
                        "detections": int(band_tp_det[b] + band_fp[b]), "precision": p_b})
    return {"frames": n_img, "classes": list(target_classes), "score_threshold": score_threshold,
            "ground_truth": n_gt, "true_positives": tp, "false_positives": fp,
            "precision": precision, "recall": recall, "false_alarms_per_frame": fp / n_img if n_img else 0.0,
            "ap50": ap50, "ap50_95": ap, "map50": ap50, "map50_95": ap, "ap50_by_class": by_class,
            "ap50_scored_apart": apart, "layout": folder.layout, "by_range_band": by_band,
            "frames_per_s": n_img / infer_s if infer_s > 0 else float("nan"),
            **({"pr50_by_class": {coco_gt.loadCats(c)[0]["name"]: curves.get(c) for c in target_cats}}
               if pr_curves and coco_dets and coco_ap else {})}


def range_bands_for(images: Sequence[dict]) -> tuple[float, ...]:
    """Range band edges for a set's frames, m: :data:`DEFAULT_RANGE_BANDS_M` (10 m bands) for
    windows reaching beyond 10 m, else four equal bands of the farthest window (a tank's)."""
    far = max((float(im["fan_geometry"]["range_max_m"]) for im in images if "fan_geometry" in im), default=math.inf)
    if far > 10.0:
        return DEFAULT_RANGE_BANDS_M
    step = math.ceil(far / 4.0 * 10.0)  # in 0.1 m
    return (0.0, step / 10.0, 2 * step / 10.0, 3 * step / 10.0, math.inf)


def _coco_ap(coco_gt, coco_dets: list[dict], img_ids: list[int], cat_ids: list[int], n_mean: int
             ) -> tuple[float, dict[int, float | None], dict[int, list[float] | None]]:
    """One COCOeval on ``cat_ids``: (AP50:95 over the first ``n_mean`` of them, as COCOeval's
    summary forms it over those categories; AP50 per category id, None for a category without
    ground truth in ``img_ids``; the precision at IoU 0.5 at COCOeval's 101 recall points
    0, 0.01 .. 1 per category id, 0 beyond the largest recall reached, None as for AP50)."""
    from pycocotools.cocoeval import COCOeval

    with contextlib.redirect_stdout(io.StringIO()):
        coco_dt = coco_gt.loadRes(coco_dets)
        ev = COCOeval(coco_gt, coco_dt, "bbox")
        ev.params.imgIds = img_ids
        ev.params.catIds = cat_ids
        ev.evaluate()
        ev.accumulate()
    prec = ev.eval["precision"]  # (IoU thresholds, recall points, categories, areas, max dets)
    per_cat, curves = {}, {}
    for k, cat in enumerate(ev.params.catIds):
        p = prec[0, :, k, 0, -1]
        per_cat[cat] = float(p[p > -1].mean()) if (p > -1).any() else None
        curves[cat] = [round(float(v), 4) for v in p] if (p > -1).any() else None
    kept = prec[:, :, :n_mean, 0, -1]  # all areas, the most detections: COCOeval's stats[0]
    ap = float(kept[kept > -1].mean()) if (kept > -1).any() else -1.0
    return ap, per_cat, curves


class _MemoDetector:
    """Caches ``detect`` results by fan content so a threshold sweep runs inference once."""

    def __init__(self, detector) -> None:
        self._detector = detector
        self._cache: dict[bytes, list] = {}

    def detect(self, frame: FlsFrame, score_threshold: float):
        import hashlib

        key = hashlib.blake2b(frame.fan.tobytes(), digest_size=16).digest() + repr(score_threshold).encode()
        if key not in self._cache:
            self._cache[key] = self._detector.detect(frame, score_threshold=score_threshold)
        return self._cache[key]


def choose_threshold(sweep: Sequence[dict], min_precision: float = 0.95, min_recall: float = 0.90) -> dict | None:
    """Operating point from a :func:`threshold_sweep`: the best F1 among the thresholds that
    reach both ``min_precision`` and ``min_recall``, else the best F1 overall. Only thresholds
    with at least one true detection (precision defined, recall above 0) are candidates; None
    when no threshold has one (nothing to choose: the detector finds no target there)."""

    def f1(r: dict) -> float:
        p, q = r["precision"], r["recall"]
        return 2 * p * q / (p + q)

    found = [r for r in sweep if r["precision"] is not None and r["recall"] is not None and r["recall"] > 0]
    ok = [r for r in found if r["precision"] >= min_precision and r["recall"] >= min_recall]
    return max(ok or found, key=f1) if found else None


def threshold_sweep(detector, data_dir: str | Path, thresholds: Sequence[float], **kwargs) -> list[dict]:
    """Precision, recall and false alarms per frame of ``detector`` on ``data_dir`` at each
    threshold (inference runs once). ``kwargs`` go to :func:`evaluate_detector`."""
    memo = _MemoDetector(detector)
    out = []
    for thr in thresholds:
        r = evaluate_detector(memo, data_dir, float(thr), coco_ap=False, **kwargs)
        out.append({k: r[k] for k in ("score_threshold", "precision", "recall", "false_alarms_per_frame",
                                      "true_positives", "false_positives", "ground_truth")})
    return out


HELDOUT_SEED = 1009
HELDOUT_FRAMES = 200


def heldout_dir(seed: int = HELDOUT_SEED, n_frames: int = HELDOUT_FRAMES) -> Path:
    """Cache directory of the default held-out set (``$AUVSIM_CACHE`` or ``~/.cache/auvsim``)."""
    from sim.dataset.generate import GENERATOR_VERSION

    import os

    root = Path(os.environ.get("AUVSIM_CACHE", Path.home() / ".cache" / "auvsim"))
    return root / f"atr_heldout_v{GENERATOR_VERSION}_seed{seed}_n{n_frames}"


def ensure_heldout(seed: int = HELDOUT_SEED, n_frames: int = HELDOUT_FRAMES, workers: int | None = None,
                   progress: bool = True) -> Path:
    """Generate (or finish) the held-out set: seed and randomisation ranges unused in training."""
    from sim.dataset.generate import generate_dataset
    from sim.dataset.randomization import HELDOUT_RANDOMIZATION

    out = heldout_dir(seed, n_frames)
    generate_dataset(out, n_frames, seed=seed, workers=workers, randomization=HELDOUT_RANDOMIZATION,
                     progress=progress)
    return out


def bench_atr(data_dir: str | Path | None = None, n_frames: int = 50, repeats: int = 3,
              model: str | Path | None = None) -> dict:
    """Inference speed on one core: ``frames_per_s`` of the CNN and classical detectors.

    Times ``detect`` over the first ``n_frames`` frames of ``data_dir`` (default: the
    held-out set), best of ``repeats`` passes; frames are decoded before timing. With
    ``model`` (an ONNX file), that model and the shipped one also run in alternating passes
    over the same frames, timed in CPU seconds: ``model_cpu_ratio`` is the model's CPU time per
    ``detect`` (pre-processing and decoding included) over the shipped model's, from the
    ``5 * repeats`` alternated passes' medians.
    """
    from autonomy.atr import build_detector
    from autonomy.atr.config import AtrConfig

    data = Path(data_dir) if data_dir is not None else ensure_heldout(progress=False)
    coco = json.loads((data / ANNOTATIONS_FILE).read_text())
    recs = sorted(coco["images"], key=lambda r: r["id"])[:n_frames]
    frames = [frame_from_record(r, cv2.imread(str(data / r["file_name"]), cv2.IMREAD_GRAYSCALE)) for r in recs]
    out: dict = {"frames": len(frames), "fan_hw": list(frames[0].fan.shape)}
    for kind in ("cnn", "classical"):
        det = build_detector(AtrConfig(detector=kind, intra_op_threads=1))
        det.detect(frames[0])  # warm-up
        best = math.inf
        for _ in range(repeats):
            t0 = time.perf_counter()
            for f in frames:
                det.detect(f)
            best = min(best, time.perf_counter() - t0)
        out[f"{kind}_frames_per_s"] = len(frames) / best
        out[f"{kind}_ms_per_frame"] = 1000.0 * best / len(frames)
    if model is not None:
        cfg = AtrConfig(detector="cnn", intra_op_threads=1)
        pair = {"shipped": build_detector(cfg),
                "model": CnnDetector(model, score_threshold=cfg.score_threshold, intra_op_threads=1)}
        cpu: dict[str, list[float]] = {k: [] for k in pair}
        for det in pair.values():
            det.detect(frames[0])
        for i in range(5 * repeats):
            for k in (("shipped", "model") if i % 2 == 0 else ("model", "shipped")):
                t0 = time.process_time()
                for f in frames:
                    pair[k].detect(f)
                cpu[k].append((time.process_time() - t0) / len(frames))
        med = {k: float(np.median(v)) for k, v in cpu.items()}
        out.update({"model": str(model), "model_cpu_ms_per_frame": 1000.0 * med["model"],
                    "shipped_cpu_ms_per_frame": 1000.0 * med["shipped"],
                    "model_cpu_ratio": med["model"] / med["shipped"]})
    return out
