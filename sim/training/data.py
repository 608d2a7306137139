"""Loading an ``auvsim dataset`` directory (COCO json + PNG fans) into training arrays."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from sim.dataset.coco_io import ANNOTATIONS_FILE, coco_bbox_to_xyxy
from sim.dataset.labelled_folder import folder_layout, load_labelled_folder
from sim.dataset.errors import DatasetError


@dataclass
class DetectionArrays:
    """A dataset resized to the model input.

    ``images`` (N, H, W) uint8; per image, ``boxes`` (K, 4) xyxy in input px (pixel centres at
    integers), ``class_ids`` (K,) indices into ``class_names`` and ``ignore`` (K,) bool.
    """

    images: NDArray[np.uint8]
    boxes: list[NDArray[np.float64]]
    class_ids: list[NDArray[np.int64]]
    ignore: list[NDArray[np.bool_]]
    class_names: list[str]
    fan_hw: tuple[int, int]


def fan_to_input_xyxy(boxes_fan: NDArray, fan_hw: tuple[int, int], input_hw: tuple[int, int]) -> NDArray:
    """Fan px -> input px for xyxy boxes (pixel centres at integers in both)."""
    b = np.asarray(boxes_fan, dtype=np.float64).reshape(-1, 4).copy()
    sx, sy = fan_hw[1] / input_hw[1], fan_hw[0] / input_hw[0]
    b[:, [0, 2]] = (b[:, [0, 2]] + 0.5) / sx - 0.5
    b[:, [1, 3]] = (b[:, [1, 3]] + 0.5) / sy - 0.5
    return b


def load_detection_arrays(data_dir: str | Path, input_hw: tuple[int, int],
                          class_names: list[str] | None = None, input_transform: str = "resize") -> DetectionArrays:
    """Read ``data_dir``'s COCO file and PNGs, resized to ``input_hw`` with INTER_AREA
    (``input_transform="resize"``) or placed at native resolution in the top-left corner of a
    zero ``input_hw`` image (``"pad"``, boxes unchanged; see
    :class:`autonomy.atr.cnn_detector.CnnDetector`).

    Raises:
        ValueError: with ``"pad"``, a fan larger than ``input_hw``; images of different sizes.
        FileNotFoundError: no annotations file, or an image that cannot be read.
    """
    data_dir = Path(data_dir)
    if not data_dir.is_dir() or folder_layout(data_dir) is None:
        raise FileNotFoundError(f"no {ANNOTATIONS_FILE} (nor images/ and boxes/) in dataset directory {data_dir}")
    folder = load_labelled_folder(data_dir)
    coco = folder.coco
    cats = {c["id"]: c["name"] for c in coco["categories"]}
    names = class_names if class_names is not None else [cats[k] for k in sorted(cats)]
    name_to_idx = {n: i for i, n in enumerate(names)}
    by_image: dict[int, list[dict]] = {}
    for a in coco["annotations"]:
        by_image.setdefault(a["image_id"], []).append(a)
    images, boxes, cls, ign = [], [], [], []
    fan_hw = None
    h, w = input_hw
    for im in sorted(coco["images"], key=lambda r: r["id"]):
        fan = cv2.imread(str(folder.root / im["file_name"]), cv2.IMREAD_GRAYSCALE)
        if fan is None:
            raise FileNotFoundError(f"dataset {data_dir}: cannot read image {im['file_name']}")
        if fan_hw is None:
            fan_hw = fan.shape
        elif fan.shape != fan_hw:
            raise ValueError(f"dataset {data_dir}: image {im['file_name']} is {fan.shape}, others {fan_hw}")
        anns = [a for a in by_image.get(im["id"], []) if cats[a["category_id"]] in name_to_idx]
        xyxy = coco_bbox_to_xyxy(np.array([a["bbox"] for a in anns], dtype=np.float64).reshape(-1, 4))
        if input_transform == "pad":
            if fan.shape[0] > h or fan.shape[1] > w:
                raise ValueError(f"dataset {data_dir}: fan {fan.shape[1]} x {fan.shape[0]} px is larger than the "
                                 f"input {w} x {h} it is padded into")
            padded = np.zeros((h, w), np.uint8)
            padded[:fan.shape[0], :fan.shape[1]] = fan
            images.append(padded)
            boxes.append(xyxy)
        else:
            images.append(cv2.resize(fan, (w, h), interpolation=cv2.INTER_AREA))
            boxes.append(fan_to_input_xyxy(xyxy, fan_hw, input_hw))
        cls.append(np.array([name_to_idx[cats[a["category_id"]]] for a in anns], dtype=np.int64))
        ign.append(np.array([bool(a.get("iscrowd", 0)) for a in anns], dtype=bool))
    if not images:
        raise ValueError(f"dataset {data_dir} has no images")
    return DetectionArrays(np.stack(images), boxes, cls, ign, list(names), tuple(fan_hw))


def labelled_class_counts(data_dir: str | Path) -> dict[str, int]:
    """Class name -> labelled (not ``iscrowd``) objects in ``data_dir``'s labels (either layout,
    :mod:`sim.dataset.labelled_folder`), for every category it lists (0 for a category without
    one), in category id order."""
    coco = load_labelled_folder(data_dir).coco
    cats = {c["id"]: c["name"] for c in coco["categories"]}
    counts = {cats[k]: 0 for k in sorted(cats)}
    for a in coco["annotations"]:
        if not a.get("iscrowd", 0) and a["category_id"] in cats:
            counts[cats[a["category_id"]]] += 1
    return counts


def check_training_classes(data_dirs: list[Path], classes: tuple[str, ...] | list[str] | None,
                           arg: str = "--classes") -> None:
    """Refuse classes a training run could not learn, before any image is loaded.

    Raises:
        DatasetError: ``classes`` holds an empty or repeated name, or a class with no labelled
            object in the datasets (the message lists the classes present, with their counts);
            or the datasets list different classes.
    """
    counts = [labelled_class_counts(d) for d in data_dirs]
    for d, c in zip(data_dirs[1:], counts[1:]):
        if list(c) != list(counts[0]):
            raise DatasetError(f"--data {d}: has classes {', '.join(c)}, {data_dirs[0]} has "
                               f"{', '.join(counts[0])}; train on datasets of the same classes")
    total = {k: sum(c.get(k, 0) for c in counts) for k in counts[0]}
    present = ", ".join(f"{k} ({n} labelled)" for k, n in total.items() if n) or "none labelled"
    where = data_dirs[0] if len(data_dirs) == 1 else f"the {len(data_dirs)} datasets"
    if classes is None:
        if not any(total.values()):
            raise DatasetError(f"--data {where}: holds no labelled object (classes listed: {', '.join(total)})")
        return
    names = list(classes)
    if not names or any(not n for n in names):
        raise DatasetError(f"{arg} {','.join(names)}: has an empty class name; give names from the data: {present}")
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise DatasetError(f"{arg} {','.join(names)}: names {', '.join(repeated)} more than once")
    missing = [n for n in names if not total.get(n)]
    if missing:
        raise DatasetError(f"{arg} {','.join(names)}: no labelled object of class {', '.join(missing)} in {where}; "
                           f"classes present: {present}")

