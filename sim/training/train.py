"""``auvsim train-atr``: train the CenterNet-style ATR detector on a dataset and export ONNX."""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from sim.training import require_torch
from sim.dataset.errors import DatasetError, fls_fan_hw
from sim.training.targets import encode_targets

DEFAULT_INPUT_HW = (240, 448)
#: The architectures of :data:`sim.training.model.ARCHITECTURES` (named here without torch).
ARCH_NAMES = ("s4", "s8")


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
    crop_hw: tuple[int, int] | None = (128, 224)
    object_crop_fraction: float = 0.75
    size_loss_weight: float = 0.5
    light_heads: bool = False
    #: model architecture, a key of :data:`sim.training.model.ARCHITECTURES`
    arch: str = "s4"
    #: how a fan becomes the input: ``resize`` (INTER_AREA) or ``pad`` (native resolution)
    input_transform: str = "resize"
    #: training-image augmentation, a key of :data:`AUGMENTATIONS`
    augment: str = "basic"


#: ``--augment`` choices: ``basic`` flips and draws gain and gamma; ``sonar`` adds, before
#: them, a random image formation (:func:`_sonar_formation`) so a network trained on synthetic
#: frames does not learn one renderer's speckle and resolution (domain randomisation,
#: [Tobin2017]).
AUGMENTATIONS = ("basic", "sonar")


#: Parameters a resumed run may change (the others define the run and must match).
RESUMABLE_CHANGES = ("threads",)
#: Parameters added after the checkpoint format was fixed: a checkpoint without one ran with its default.
ADDED_PARAMS = ("augment",)
#: Checkpoint file format tag.
CHECKPOINT_FORMAT = "auvsim-train-atr-checkpoint-1"


def _focal_loss(torch, logits, target, weight):
    """CenterNet penalty-reduced focal loss (alpha 2, beta 4), normalised by object count."""
    p = torch.sigmoid(logits).clamp(1e-4, 1 - 1e-4)
    pos = (target >= 0.999).float()
    neg_w = (1 - target) ** 4
    w = weight[:, None]
    pos_loss = -(torch.log(p) * (1 - p) ** 2 * pos * w).sum()
    neg_loss = -(torch.log(1 - p) * p ** 2 * neg_w * (1 - pos) * w).sum()
    return (pos_loss + neg_loss) / pos.sum().clamp(min=1.0)


def _crop_batch(images: np.ndarray, boxes: list, class_ids: list, ignore: list, idx: np.ndarray,
                crop_hw: tuple[int, int], rng: np.random.Generator, object_fraction: float):
    """Crops of ``crop_hw`` from images ``idx``: most centred near a random labelled object
    (jittered), the rest anywhere. Returns (crops (B, h, w) uint8, boxes, class ids, ignore)."""
    h_img, w_img = images.shape[1:]
    ch, cw = crop_hw
    crops, out_b, out_c, out_i = [], [], [], []
    for i in idx:
        b = boxes[i]
        real = np.flatnonzero(~ignore[i])
        if real.size and rng.random() < object_fraction:
            k = real[rng.integers(real.size)]
            cx = 0.5 * (b[k, 0] + b[k, 2]) + rng.uniform(-0.4, 0.4) * cw
            cy = 0.5 * (b[k, 1] + b[k, 3]) + rng.uniform(-0.4, 0.4) * ch
            x0 = int(np.clip(round(cx - cw / 2), 0, w_img - cw))
            y0 = int(np.clip(round(cy - ch / 2), 0, h_img - ch))
        else:
            x0 = int(rng.integers(0, w_img - cw + 1))
            y0 = int(rng.integers(0, h_img - ch + 1))
        crops.append(images[i, y0:y0 + ch, x0:x0 + cw])
        shifted = b - np.array([x0, y0, x0, y0], dtype=np.float64)
        clipped = shifted.copy()
        clipped[:, [0, 2]] = clipped[:, [0, 2]].clip(-0.5, cw - 0.5)
        clipped[:, [1, 3]] = clipped[:, [1, 3]].clip(-0.5, ch - 0.5)
        area = np.prod(np.clip(shifted[:, 2:] - shifted[:, :2], 1e-9, None), axis=1)
        kept_area = np.prod(np.clip(clipped[:, 2:] - clipped[:, :2], 0.0, None), axis=1)
        inside = kept_area > 0
        # objects cut by the crop border are ignored (neither positive nor negative)
        cut = inside & (kept_area < 0.7 * area)
        out_b.append(clipped[inside])
        out_c.append(class_ids[i][inside])
        out_i.append(ignore[i][inside] | cut[inside])
    return np.stack(crops), out_b, out_c, out_i


#: ``sonar`` augmentation ranges, drawn per crop (uniform): the share of crops it touches,
#: the Gaussian blur sigma along each image axis (px), the multiplicative log-normal speckle's
#: sigma, the additive noise sigma (grey / 255) and the contrast factor about the crop mean.
SONAR_FORMATION = {"probability": 0.8, "blur_sigma_px": (0.0, 1.5), "speckle_sigma": (0.0, 0.5),
                   "noise_sigma": (0.0, 0.04), "contrast": (0.7, 1.4)}


def _gaussian_taps(torch, sigma: float, radius: int = 4):
    """Normalised 1-D Gaussian taps of ``sigma`` px on ``2 radius + 1`` points (a delta for 0)."""
    x = np.arange(-radius, radius + 1, dtype=np.float64)
    k = np.exp(-0.5 * (x / sigma) ** 2) if sigma > 1e-3 else (x == 0).astype(np.float64)
    return torch.from_numpy((k / k.sum()).astype(np.float32))


def _sonar_formation(torch, imgs, rng: np.random.Generator):
    """A random image formation for each crop of ``imgs`` ((B, 1, H, W) float in [0, 1]):
    multiplicative log-normal speckle (mean 1), then a separable Gaussian blur along each axis
    (so the speckle is correlated over a random length, as a longer pulse and wider beams give),
    additive noise, and a contrast change about the crop's mean. Ranges in
    :data:`SONAR_FORMATION`; a crop is left alone with probability ``1 - probability``. Boxes
    do not move. Draws from ``rng`` (parameters) and torch's generator (noise fields), both in
    the checkpoint, so a resumed run draws the same."""
    f = SONAR_FORMATION
    out = imgs.clone()
    for i in range(imgs.shape[0]):
        if rng.random() >= f["probability"]:
            continue
        sy, sx = rng.uniform(*f["blur_sigma_px"], size=2)
        s_speckle, s_noise = rng.uniform(*f["speckle_sigma"]), rng.uniform(*f["noise_sigma"])
        contrast = rng.uniform(*f["contrast"])
        x = out[i:i + 1]
        if s_speckle > 0:
            x = x * torch.exp(s_speckle * torch.randn_like(x) - 0.5 * s_speckle ** 2)
        ky, kx = _gaussian_taps(torch, sy), _gaussian_taps(torch, sx)
        r = ky.numel() // 2
        x = torch.nn.functional.pad(x, (r, r, r, r), mode="replicate")
        x = torch.nn.functional.conv2d(x, ky.view(1, 1, -1, 1))
        x = torch.nn.functional.conv2d(x, kx.view(1, 1, 1, -1))
        x = x + s_noise * torch.randn_like(x)
        m = x.mean()
        out[i:i + 1] = ((x - m) * contrast + m).clamp(0, 1)
    return out


def _augment(torch, imgs, boxes_list, rng: np.random.Generator, width: int, kind: str = "basic"):
    """Random horizontal flip (the fan is symmetric about its centre column) and gain/gamma;
    ``kind`` ``sonar`` first draws a random image formation (:func:`_sonar_formation`)."""
    if kind == "sonar":
        imgs = _sonar_formation(torch, imgs, rng)
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


def _lr_at(progress: float, peak: float, warmup: float = 0.05, final_fraction: float = 0.02) -> float:
    """Learning rate at training ``progress`` in [0, 1]: linear warm-up, cosine decay."""
    if progress < warmup:
        return peak * (0.1 + 0.9 * progress / warmup)
    q = (progress - warmup) / (1.0 - warmup)
    return peak * (final_fraction + (1.0 - final_fraction) * 0.5 * (1.0 + np.cos(np.pi * q)))


def _log(msg: str) -> None:
    print(msg, flush=True)


def _load_all(data_dirs: list[Path], input_hw: tuple[int, int], classes, input_transform: str = "resize"):
    """Load and concatenate several dataset directories (class lists must agree)."""
    from sim.training.data import DetectionArrays, load_detection_arrays

    parts = [load_detection_arrays(d, input_hw, classes, input_transform) for d in data_dirs]
    first = parts[0]
    for d, a in zip(data_dirs[1:], parts[1:]):
        if a.class_names != first.class_names or a.fan_hw != first.fan_hw:
            raise DatasetError(f"train-atr: dataset {d} has classes {a.class_names} / fan {a.fan_hw}, "
                             f"{data_dirs[0]} has {first.class_names} / {first.fan_hw}")
    if len(parts) == 1:
        return first
    return DetectionArrays(np.concatenate([a.images for a in parts]), sum((a.boxes for a in parts), []),
                           sum((a.class_ids for a in parts), []), sum((a.ignore for a in parts), []),
                           first.class_names, first.fan_hw)


#: Frames the end-of-training check runs the exported model on.
CHECK_FRAMES = 32


def detection_check(model_path: str | Path, data_dirs: list[Path], classes: list[str],
                    score_threshold: float, n_frames: int = CHECK_FRAMES) -> dict:
    """Run the exported model on the first ``n_frames`` frames (by image id, over
    ``data_dirs`` in turn) that hold a labelled (not ``iscrowd``) object of ``classes``.

    Returns:
        ``frames``, ``labelled_objects`` (of ``classes`` in them), ``detections`` (of
        ``classes`` at ``score_threshold``), ``score_threshold``, ``data`` (the folders).
    """
    import cv2

    from autonomy.atr.cnn_detector import CnnDetector
    from sim.dataset.labelled_folder import load_labelled_folder
    from sim.evaluation.atr_metrics import frame_from_record

    det = CnnDetector(model_path, score_threshold=score_threshold, classes=tuple(classes))
    frames = objects = detections = 0
    for d in data_dirs:
        folder = load_labelled_folder(d)
        coco = folder.coco
        cats = {c["id"] for c in coco["categories"] if c["name"] in classes}
        by_image: dict[int, int] = {}
        for a in coco["annotations"]:
            if a["category_id"] in cats and not a.get("iscrowd", 0):
                by_image[a["image_id"]] = by_image.get(a["image_id"], 0) + 1
        for rec in sorted(coco["images"], key=lambda r: r["id"]):
            if frames >= n_frames:
                break
            if rec["id"] not in by_image:
                continue
            fan = cv2.imread(str(folder.root / rec["file_name"]), cv2.IMREAD_GRAYSCALE)
            if fan is None:
                continue
            frames += 1
            objects += by_image[rec["id"]]
            detections += len(det.detect(frame_from_record(rec, fan)))
    return {"frames": frames, "labelled_objects": objects, "detections": detections,
            "score_threshold": float(score_threshold), "data": [str(d) for d in data_dirs]}


class CheckpointError(ValueError):
    """A checkpoint that cannot be resumed: wrong format, or another run's parameters or data."""


def _save_checkpoint(torch, path: Path, state: dict) -> None:
    """Write ``state`` to ``path`` atomically (a crash mid-write keeps the previous one)."""
    tmp = path.with_name(path.name + ".tmp")
    path.parent.mkdir(parents=True, exist_ok=True)
    torch.save(state, tmp)
    tmp.replace(path)


def _read_checkpoint(torch, path: Path, flag: str) -> dict:
    """A train-atr checkpoint file's state.

    Raises:
        CheckpointError: unreadable, or not a train-atr checkpoint (named by ``flag``).
    """
    try:
        state = torch.load(path, map_location="cpu", weights_only=False)
    except Exception as exc:  # torch raises several exception types for bad files
        raise CheckpointError(f"{flag} {path}: cannot be read as a checkpoint ({type(exc).__name__})") from None
    if not isinstance(state, dict) or state.get("format") != CHECKPOINT_FORMAT:
        raise CheckpointError(f"{flag} {path}: not a train-atr checkpoint")
    return state


def _load_checkpoint(torch, path: Path, params: TrainParams, data_dirs: list[Path], n_img: int) -> dict:
    """Read a checkpoint and check it belongs to this run (parameters and data)."""
    state = _read_checkpoint(torch, path, "--checkpoint")
    saved = state["params"]
    now, default = asdict(params), asdict(TrainParams())
    saved = {k: saved.get(k, default[k]) if k in ADDED_PARAMS else saved.get(k) for k in now}
    diff = [f"{k} {saved.get(k)!r} -> {now[k]!r}" for k in now
            if k not in RESUMABLE_CHANGES and json.dumps(saved.get(k), default=list) != json.dumps(now[k], default=list)]
    if diff:
        raise CheckpointError(f"--resume {path}: the run was started with other parameters ({'; '.join(diff)}); "
                              "give the same ones (only --threads may change)")
    dirs = [str(d) for d in data_dirs]
    if state["data_dirs"] != dirs or state["n_images"] != n_img:
        raise CheckpointError(f"--resume {path}: the run was started on {','.join(state['data_dirs'])} "
                              f"({state['n_images']} images), not {','.join(dirs)} ({n_img} images)")
    return state


def _init_weights(torch, model, path: Path, params: TrainParams, class_names) -> None:
    """Start ``model`` from the network of another run's checkpoint (pretraining: e.g. on
    synthetic frames, then fine-tuned on real ones); its optimiser and schedule are not taken.

    Raises:
        CheckpointError: not a readable checkpoint, another architecture, width or heads, or
            other classes (names where the checkpoint records them, else their number).
    """
    state = _read_checkpoint(torch, path, "--init-from")
    saved = state["params"]
    diff = [f"{k} {saved.get(k)!r} (this run: {getattr(params, k)!r})" for k in ("arch", "width", "light_heads")
            if saved.get(k) != getattr(params, k)]
    if diff:
        raise CheckpointError(f"--init-from {path}: its network differs: {'; '.join(diff)}")
    names = state.get("class_names")
    if names is not None and list(names) != list(class_names):
        raise CheckpointError(f"--init-from {path}: its classes are {', '.join(names)}, this run's "
                              f"{', '.join(class_names)}; train on data of the same classes (--classes)")
    try:
        model.load_state_dict(state["model"])
    except RuntimeError:
        raise CheckpointError(f"--init-from {path}: its network does not fit this run's (another number of "
                              f"classes than {len(class_names)}?)") from None


def train_atr(data_dir: str | Path | list, out_path: str | Path, params: TrainParams = TrainParams(),
              log=_log, val_data: str | Path | list | None = None, checkpoint: str | Path | None = None,
              resume: bool = False, checkpoint_minutes: float = 5.0, stop_after_minutes: float | None = None,
              init_from: str | Path | None = None) -> dict:
    """Train on ``data_dir`` (a labelled folder of either layout, :mod:`sim.dataset.labelled_folder`,
    or a list of them, concatenated) and export ONNX to ``out_path``.

    Stops after ``params.epochs`` epochs or ``params.max_minutes`` of training (summed over
    resumed sessions), whichever comes first; the learning-rate schedule runs over the same.
    With ``checkpoint``, the whole training state (model, optimiser, random generators,
    position in the epoch) is saved there every ``checkpoint_minutes`` and when the run stops;
    ``resume`` continues from it (same parameters and data; a resumed run takes the same steps
    as an unbroken one). ``stop_after_minutes`` ends this session early (checkpoint saved,
    model exported as it stands) without ending the run. ``init_from`` starts the network
    from another run's checkpoint (pretraining; same architecture, width, heads and classes),
    with a new optimiser and schedule.
    Then runs the model at the default operating threshold (``AtrConfig.score_threshold``) on
    up to :data:`CHECK_FRAMES` frames holding labelled objects of ``val_data`` (folders
    held out of training; None: of the training data), :func:`detection_check`.

    Returns:
        a summary dict (epochs run, final losses, seconds, parameter count, ``check``: the
        detection check; ``check["detections"] == 0``: the model detects nothing there).

    Raises:
        sim.dataset.errors.DatasetError: ``params.classes`` names a class without a labelled
            object in the data, or the datasets disagree on classes or fan size (before any
            training).
        FileNotFoundError: a folder has no annotations file, or ``resume`` without a
            checkpoint file.
        CheckpointError: ``resume`` from a checkpoint of another run; ``init_from`` a
            checkpoint whose network does not fit.
        ValueError: an unknown ``arch`` or ``input_transform``.
    """
    torch = require_torch()
    from autonomy.atr.config import AtrConfig
    from sim.training.data import check_training_classes
    from sim.training.export import export_onnx
    from sim.training.model import ARCHITECTURES

    torch.manual_seed(params.seed)
    torch.set_num_threads(params.threads)
    rng = np.random.default_rng(params.seed)
    t0 = time.perf_counter()
    data_dirs = [Path(d) for d in (data_dir if isinstance(data_dir, (list, tuple)) else [data_dir])]
    val_dirs = None if val_data is None else [Path(d) for d in (val_data if isinstance(val_data, (list, tuple))
                                                                else [val_data])]
    from sim.dataset.coco_io import ANNOTATIONS_FILE
    from sim.dataset.labelled_folder import folder_layout

    if params.augment not in AUGMENTATIONS:
        raise ValueError(f"augment {params.augment!r}: expected one of {', '.join(AUGMENTATIONS)}")

    for d in data_dirs + (val_dirs or []):
        if not d.is_dir() or folder_layout(d) is None:
            raise FileNotFoundError(f"no {ANNOTATIONS_FILE} (nor images/ and boxes/) in dataset directory {d}")
    check_training_classes(data_dirs, params.classes)
    fans = {d: fls_fan_hw(d, "--data") for d in data_dirs}
    if val_dirs is not None:
        try:
            check_training_classes(val_dirs, params.classes or None)
        except DatasetError as exc:
            raise DatasetError(f"--val-data: {exc}") from None
        fans.update({d: fls_fan_hw(d, "--val-data") for d in val_dirs})
    if len(set(fans.values())) > 1:
        raise DatasetError("--data / --val-data: the datasets hold fans of different sizes ("
                           + ", ".join(f"{d}: {w} x {h} px" for d, (h, w) in fans.items())
                           + "); a model is trained and checked on one sonar's fans")
    if params.arch not in ARCHITECTURES:
        raise ValueError(f"arch {params.arch!r}: expected one of {', '.join(ARCHITECTURES)}")
    if params.input_transform not in ("resize", "pad"):
        raise ValueError(f"input_transform {params.input_transform!r}: expected resize or pad")
    ckpt_path = None if checkpoint is None else Path(checkpoint)
    if resume and (ckpt_path is None or not ckpt_path.is_file()):
        raise FileNotFoundError(f"--resume: no checkpoint file {ckpt_path}")
    arrays = _load_all(data_dirs, params.input_hw, list(params.classes) if params.classes else None,
                       params.input_transform)
    n_img = arrays.images.shape[0]
    h, w = params.input_hw
    if h % 16 or w % 16:
        raise ValueError(f"input_hw {params.input_hw}: height and width must be multiples of 16")
    crop = params.crop_hw or params.input_hw
    crop = (min(crop[0], h), min(crop[1], w))
    if crop[0] % 16 or crop[1] % 16:
        raise ValueError(f"crop_hw {crop}: height and width must be multiples of 16")
    model = ARCHITECTURES[params.arch](len(arrays.class_names), params.width, light_heads=params.light_heads)
    stride = model.stride
    grid = (crop[0] // stride, crop[1] // stride)
    n_params = sum(p.numel() for p in model.parameters())
    opt = torch.optim.AdamW(model.parameters(), lr=params.lr, weight_decay=params.weight_decay)
    steps_per_epoch = max(1, int(np.ceil(n_img / params.batch_size)))
    total_steps = params.epochs * steps_per_epoch
    log(f"train-atr: {n_img} images, crops {crop}, classes {arrays.class_names}, {n_params} parameters, "
        f"input {h}x{w}, augment {params.augment}, load {time.perf_counter() - t0:.1f} s")
    budget_s = 60.0 * params.max_minutes
    history: list[dict] = []
    epoch, step, s_start, elapsed0 = 1, 0, 0, 0.0
    order = None
    sums = np.zeros(3)
    if init_from is not None:
        _init_weights(torch, model, Path(init_from), params, arrays.class_names)
        log(f"train-atr: network initialised from {init_from}")
    if resume:
        state = _load_checkpoint(torch, ckpt_path, params, data_dirs, n_img)
        model.load_state_dict(state["model"])
        opt.load_state_dict(state["optimizer"])
        rng.bit_generator.state = state["numpy_rng"]
        torch.set_rng_state(state["torch_rng"])
        epoch, step, s_start, elapsed0 = state["epoch"], state["step"], state["step_in_epoch"], state["elapsed_s"]
        # an epoch-boundary checkpoint has no order yet: the next epoch draws its own
        order = None if state["order"] is None else np.asarray(state["order"])
        sums, history = np.asarray(state["sums"]), state["history"]
        if epoch > params.epochs:
            log(f"train-atr: {ckpt_path} holds a finished run ({step} steps, {elapsed0 / 60:.1f} min trained); "
                "nothing to train, its model is exported again")
        else:
            log(f"train-atr: resumed {ckpt_path} at epoch {epoch}, step {step} of {total_steps} "
                f"({elapsed0 / 60:.1f} min trained)")
    t_session = time.perf_counter()
    session_deadline = None if stop_after_minutes is None else t_session + 60.0 * stop_after_minutes
    last_save = t_session

    def elapsed() -> float:
        return elapsed0 + (time.perf_counter() - t_session)

    def save(epoch_now: int, s_next: int) -> None:
        _save_checkpoint(torch, ckpt_path, {
            "format": CHECKPOINT_FORMAT, "params": asdict(params), "data_dirs": [str(d) for d in data_dirs],
            "class_names": list(arrays.class_names),
            "n_images": n_img, "model": model.state_dict(), "optimizer": opt.state_dict(),
            "numpy_rng": rng.bit_generator.state, "torch_rng": torch.get_rng_state(), "epoch": epoch_now,
            "step": step, "step_in_epoch": s_next, "elapsed_s": elapsed(),
            "order": None if order is None else order.tolist(), "sums": sums.tolist(), "history": history})

    model.train()
    stopped_early = session_stop = False
    finished = epoch > params.epochs
    while not finished:
        if order is None:
            order = rng.permutation(n_img)
            sums = np.zeros(3)
        for s in range(s_start, steps_per_epoch):
            idx = order[s * params.batch_size:(s + 1) * params.batch_size]
            if idx.size == 0:
                continue
            crops, boxes, cls_b, ign_b = _crop_batch(arrays.images, arrays.boxes, arrays.class_ids, arrays.ignore,
                                                     idx, crop, rng, params.object_crop_fraction)
            imgs = torch.from_numpy(crops.astype(np.float32) / 255.0)[:, None]
            imgs, boxes = _augment(torch, imgs, boxes, rng, crop[1], params.augment)
            tg = [encode_targets(boxes[k], cls_b[k], ign_b[k], len(arrays.class_names), grid, stride)
                  for k in range(len(idx))]
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
            loss = l_heat + params.size_loss_weight * l_size + l_off
            # Warm-up then cosine decay over whichever runs out first: steps or the time budget.
            # (the time term waits for the first step, so a budget that does not bind never
            # touches the schedule and reruns are step for step the same)
            progress = step / total_steps if step == 0 else max(step / total_steps, elapsed() / budget_s)
            for group in opt.param_groups:
                group["lr"] = _lr_at(min(progress, 1.0), params.lr)
            opt.zero_grad()
            loss.backward()
            opt.step()
            step += 1
            sums += [l_heat.item(), l_size.item(), l_off.item()]
            if elapsed() > budget_s:
                stopped_early = True
                s_start = s + 1
                break
            now = time.perf_counter()
            if session_deadline is not None and now > session_deadline:
                session_stop = True
                s_start = s + 1
                break
            if ckpt_path is not None and now - last_save > 60.0 * checkpoint_minutes:
                save(epoch, s + 1)
                last_save = now
        else:
            s_start = steps_per_epoch
        if s_start >= steps_per_epoch or stopped_early:
            mean = sums / steps_per_epoch
            history.append({"epoch": epoch, "heat": mean[0], "size": mean[1], "offset": mean[2]})
            log(f"epoch {epoch}: heat {mean[0]:.3f} size {mean[1]:.3f} offset {mean[2]:.3f} "
                f"({elapsed():.0f} s trained)")
            epoch += 1
            order, s_start = None, 0
        finished = stopped_early or epoch > params.epochs
        if stopped_early:
            log(f"train-atr: time budget of {params.max_minutes} min reached")
        if ckpt_path is not None and (finished or session_stop or s_start == 0):
            save(epoch, s_start)
            last_save = time.perf_counter()
        if session_stop:
            log(f"train-atr: stopped after {stop_after_minutes} min this session at epoch {epoch}, step {step} "
                f"of {total_steps}; continue with --resume")
            break
    epoch = epoch - 1 if s_start == 0 else epoch
    model.eval()
    train_data = []
    for d in data_dirs:
        manifest_path = d / "manifest.json"
        m = json.loads(manifest_path.read_text()) if manifest_path.is_file() else {}
        train_data.append({"dir": str(d), "n_frames": m.get("n_frames"),
                           "generator_version": m.get("generator_version"), "seed": m.get("seed")})
    meta = {"train_params": json.dumps({k: v for k, v in asdict(params).items()}, default=list),
            "train_data": json.dumps({"dir": ",".join(str(d) for d in data_dirs), "n_images": n_img,
                                      "generator_version": train_data[0]["generator_version"],
                                      "seed": train_data[0]["seed"] if len(train_data) == 1
                                      else [t["seed"] for t in train_data], "datasets": train_data}),
            "epochs_run": str(epoch)}
    export_onnx(model, out_path, params.input_hw, arrays.fan_hw, arrays.class_names, meta,
                input_transform=params.input_transform)
    model.train()
    summary = {"epochs_run": epoch, "seconds": time.perf_counter() - t0, "training_seconds": elapsed(),
               "steps": step, "total_steps": total_steps, "parameters": n_params,
               "images": n_img, "classes": arrays.class_names, "history": history,
               "out": str(out_path), "stopped_on_time": stopped_early, "finished": finished and not session_stop}
    log(f"train-atr: wrote {out_path} after {summary['seconds']:.0f} s")
    check = summary["check"] = detection_check(out_path, val_dirs or data_dirs, arrays.class_names,
                                               AtrConfig().score_threshold)
    check["held_out"] = val_dirs is not None
    log(f"train-atr: at score threshold {check['score_threshold']:.2f} the model makes {check['detections']} "
        f"detection{'' if check['detections'] == 1 else 's'} on {check['frames']} "
        f"{'validation' if val_dirs is not None else 'training'} frames holding {check['labelled_objects']} "
        "labelled objects")
    return summary
