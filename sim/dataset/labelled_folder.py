"""Labelled sonar image folders read as one COCO detection document, whatever their layout.

Two layouts are read:

==============  ============================================================================
layout          what the folder holds
==============  ============================================================================
``coco``        ``annotations.json`` (COCO, written by ``auvsim dataset``) and the images it
                names; each image record carries its ``fan_geometry``
``watertank``   ``images/*.png``, ``boxes/<stem>.xml`` (Pascal-VOC-like ``object`` entries
                whose ``bndbox`` holds ``x y w h`` in pixels, COCO order), optionally
                ``masks/*.png`` (class id per pixel) and ``classes.txt``: the layout of the Marine Debris
                forward-looking sonar set ([MarineDebrisFLS]) and of real recordings labelled
                the same way
==============  ============================================================================

A watertank folder becomes a COCO document in memory: one category per class, those of its
``classes.txt`` (one name a line, ids from 1: what ``auvsim dataset`` writes) or, without one,
:data:`WATERTANK_CLASSES` (the Marine Debris set's ids); one image record per PNG (natural name order,
ids from 1) with a ``fan_geometry`` fitted to the frames' own fan outline (frames are
grouped by outline, :func:`sim.dataset.real_frames.fan_groups`, and each group fitted; the
metric scale assumes the window starts at ``near_m``, the ARIS 3000's nearest window by
default), and one annotation per box (``attributes.range_m``: the box centre's slant range
in that geometry). Readers of datasets (``auvsim eval-atr``, ``auvsim train-atr``) take
either layout through :func:`load_labelled_folder`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from autonomy.sonar_geometry import FanGeometry
from sim.dataset.coco_io import ANNOTATIONS_FILE, IMAGES_DIR, fan_geometry_record
from sim.dataset.errors import DatasetError, require_dataset
from sim.dataset.real_frames import (MARINE_DEBRIS_CLASSES, RealDataError, fan_groups, fit_fan_outline, natural_key,
                                     read_box_file, read_frame)

#: Class ids of the watertank layout ([MarineDebrisFLS]): COCO category ids.
WATERTANK_CLASSES: dict[int, str] = MARINE_DEBRIS_CLASSES
#: Classes scored apart from the objects (a tank wall is background structure, not debris).
SCORED_APART = ("Wall",)
#: Window start assumed for a watertank folder's metric scale, m (the ARIS 3000's nearest).
WATERTANK_NEAR_M = 0.7
BOXES_DIR, MASKS_DIR, CLASSES_FILE = "boxes", "masks", "classes.txt"
#: A pixel is inside the fan when lit in more than this share of a group's frames (low: frames
#: whose shadows or walls darken part of the fan still outline it together).
FAN_LIT_SHARE = 0.1
LAYOUTS = ("coco", "watertank")


@dataclass(frozen=True)
class LabelledFolder:
    """A labelled image folder as a COCO detection document.

    Attributes:
        root: the folder (resolved).
        layout: ``coco`` or ``watertank``.
        coco: the COCO document (``images`` with ``file_name`` relative to ``root``, ``width``,
            ``height`` and ``fan_geometry``; ``annotations`` with ``bbox`` [x, y, w, h] px and
            ``attributes.range_m``; ``categories``).
        target_classes: the classes scored as objects by default (``opi`` for the project's
            forward-looking datasets; every class but :data:`SCORED_APART` otherwise).
    """

    root: Path
    layout: str
    coco: dict
    target_classes: tuple[str, ...]

    @property
    def class_names(self) -> tuple[str, ...]:
        return tuple(c["name"] for c in sorted(self.coco["categories"], key=lambda c: c["id"]))

    def image(self, rec: dict) -> np.ndarray:
        """The (H, W) uint8 image of an image record.

        Raises:
            DatasetError: the image is missing or unreadable.
        """
        img = cv2.imread(str(self.root / rec["file_name"]), cv2.IMREAD_GRAYSCALE)
        if img is None:
            raise DatasetError(f"--data {self.root}: cannot read image {rec['file_name']} (missing or damaged)")
        return img


def folder_layout(path: Path) -> str | None:
    """``coco``, ``watertank`` or None (neither) for an existing folder."""
    if (path / ANNOTATIONS_FILE).is_file():
        return "coco"
    if (path / IMAGES_DIR).is_dir() and (path / BOXES_DIR).is_dir():
        return "watertank"
    return None


def load_labelled_folder(path: str | Path, arg: str = "--data", *, near_m: float = WATERTANK_NEAR_M
                         ) -> LabelledFolder:
    """Read a labelled folder of either layout (module docstring).

    Args:
        path: the folder.
        arg: the option that named it (error messages).
        near_m: watertank layout: the window start the fitted fans are scaled to, m.

    Raises:
        DatasetError: no such folder, neither layout, or a damaged label or image file (one
            line naming the file and what is expected).
    """
    root = require_dataset(path, arg)
    if folder_layout(root) == "coco":
        coco = json.loads((root / ANNOTATIONS_FILE).read_text())
        names = {c["name"] for c in coco["categories"]}
        targets = ("opi",) if "opi" in names else tuple(n for n in sorted(names) if n not in SCORED_APART)
        return LabelledFolder(root, "coco", coco, targets)
    return _watertank(root, arg, near_m)


def _fan_geometries(stack: np.ndarray, near_m: float, root: Path, arg: str) -> list[FanGeometry]:
    """Each frame's fan geometry: frames grouped by outline (two recordings exported with other
    windows), each group fitted; when a group's frames do not outline a fan on their own (dark
    parts of the fan: shadows, walls, few frames), all frames fitted as one fan."""
    geoms: list[FanGeometry] = [None] * len(stack)  # type: ignore[list-item]
    try:
        for group in fan_groups(stack):
            g = fit_fan_outline(stack[group], lit_share=FAN_LIT_SHARE).geometry(near_m)
            for i in group:
                geoms[i] = g
        return geoms
    except RealDataError:
        pass
    try:
        return [fit_fan_outline(stack, lit_share=FAN_LIT_SHARE).geometry(near_m)] * len(stack)
    except RealDataError as exc:
        raise DatasetError(f"{arg} {root}: {exc}") from None


def _watertank(root: Path, arg: str, near_m: float) -> LabelledFolder:
    paths = sorted((root / IMAGES_DIR).glob("*.png"), key=natural_key)
    if not paths:
        raise DatasetError(f"{arg} {root}: no PNG images in {IMAGES_DIR}/")
    images: list[np.ndarray] = []
    try:
        for p in paths:
            images.append(read_frame(p, images[0] if images else None))
    except RealDataError as exc:
        raise DatasetError(f"{arg} {exc}") from None
    stack = np.stack(images)
    geoms = _fan_geometries(stack, near_m, root, arg)
    classes = _folder_classes(root, arg)
    by_name = {name: cid for cid, name in classes.items()}
    coco: dict = {"images": [], "annotations": [],
                  "categories": [{"id": cid, "name": name} for cid, name in classes.items()]}
    h, w = stack.shape[1:]
    for i, (p, g) in enumerate(zip(paths, geoms), start=1):
        coco["images"].append({
            "id": i, "file_name": f"{IMAGES_DIR}/{p.name}", "width": int(w), "height": int(h),
            "fan_geometry": fan_geometry_record(g)})
        box_file = root / BOXES_DIR / f"{p.stem}.xml"
        try:
            boxes = read_box_file(box_file)
        except RealDataError as exc:
            raise DatasetError(f"{arg} {exc}") from None
        for name, (x, y, bw, bh) in ((b.class_name.strip(), b.xywh) for b in boxes):
            if name not in by_name:
                listed = (f"the classes of its {CLASSES_FILE}" if (root / CLASSES_FILE).is_file() else
                          f"the watertank classes (a folder of other classes lists them in {CLASSES_FILE})")
                raise DatasetError(f"{arg} {box_file}: class {name!r} is not one of {listed}: "
                                   f"{', '.join(classes.values())}")
            if not (bw > 0 and bh > 0 and x >= 0 and y >= 0 and x + bw <= w + 1 and y + bh <= h + 1):
                raise DatasetError(f"{arg} {box_file}: box {x:g} {y:g} {bw:g} {bh:g} (x y w h) of {name} is "
                                   f"empty or outside the {w} x {h} px image")
            cx, cy = x + 0.5 * bw - 0.5, y + 0.5 * bh - 0.5  # pixel centres at integers
            range_m = math.hypot(cx - g.apex_x_px, cy - g.apex_y_px) * g.m_per_px
            coco["annotations"].append({
                "id": len(coco["annotations"]) + 1, "image_id": i, "category_id": by_name[name],
                "bbox": [x, y, bw, bh], "area": bw * bh, "iscrowd": 0, "attributes": {"range_m": range_m}})
    targets = tuple(n for n in classes.values() if n not in SCORED_APART)
    return LabelledFolder(root, "watertank", coco, targets)


def _folder_classes(root: Path, arg: str) -> dict[int, str]:
    """Class id -> name of a watertank-layout folder: its ``classes.txt`` (one name a line, ids
    from 1, as ``auvsim dataset`` writes it) when it has one, else :data:`WATERTANK_CLASSES`."""
    path = root / CLASSES_FILE
    if not path.is_file():
        return dict(WATERTANK_CLASSES)
    try:
        names = [line.strip() for line in path.read_text().splitlines() if line.strip()]
    except (OSError, UnicodeDecodeError) as exc:
        raise DatasetError(f"{arg} {path}: not a readable text file ({exc})") from None
    if not names or len(set(names)) < len(names):
        raise DatasetError(f"{arg} {path}: must list each class name once, one a line (ids from 1)")
    return {k + 1: n for k, n in enumerate(names)}
