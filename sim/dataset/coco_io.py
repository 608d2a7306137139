"""COCO and YOLO label files for FLS fan images.

Box conventions: fan-image boxes elsewhere in auvsim are continuous xyxy with pixel
centres at integers, so a box covering pixel columns ``i0..i1`` is ``[i0 - 0.5, i1 + 0.5]``.
COCO puts pixel ``i`` on ``[i, i + 1]``; the COCO ``bbox`` of the same box is
``[i0, j0, i1 - i0 + 1, j1 - j0 + 1]``, which is what ``pycocotools.mask.toBbox`` gives
for the instance mask. YOLO lines are ``class cx cy w h`` normalised by the image size.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from pycocotools import mask as mask_utils

ANNOTATIONS_FILE = "annotations.json"
IMAGES_DIR = "images"
LABELS_DIR = "labels"


def fan_geometry_record(g) -> dict:
    """The ``fan_geometry`` of an image record: a :class:`autonomy.sonar_geometry.FanGeometry`'s
    fields (px, m, rad), what :func:`sim.evaluation.atr_metrics.frame_from_record` rebuilds."""
    return {"width_px": g.width_px, "height_px": g.height_px, "range_min_m": g.range_min_m,
            "range_max_m": g.range_max_m, "fov_rad": g.fov_rad, "m_per_px": g.m_per_px,
            "apex_x_px": g.apex_x_px, "apex_y_px": g.apex_y_px}


def xyxy_to_coco_bbox(boxes_xyxy: NDArray) -> NDArray[np.float64]:
    """Continuous xyxy (pixel centres at integers) (N, 4) -> COCO [x, y, w, h] (N, 4)."""
    b = np.asarray(boxes_xyxy, dtype=np.float64).reshape(-1, 4)
    return np.stack([b[:, 0] + 0.5, b[:, 1] + 0.5, b[:, 2] - b[:, 0], b[:, 3] - b[:, 1]], axis=1)


def coco_bbox_to_xyxy(bbox: NDArray) -> NDArray[np.float64]:
    """COCO [x, y, w, h] (N, 4) -> continuous xyxy with pixel centres at integers (N, 4)."""
    b = np.asarray(bbox, dtype=np.float64).reshape(-1, 4)
    return np.stack([b[:, 0] - 0.5, b[:, 1] - 0.5, b[:, 0] + b[:, 2] - 0.5, b[:, 1] + b[:, 3] - 0.5], axis=1)


def mask_annotation(mask: NDArray[np.bool_]) -> tuple[dict, list[float], float]:
    """(RLE segmentation with a str ``counts``, COCO bbox, area) of a binary (H, W) mask."""
    rle = mask_utils.encode(np.asfortranarray(mask.astype(np.uint8)))
    bbox = [float(v) for v in mask_utils.toBbox(rle)]
    area = float(mask_utils.area(rle))
    rle["counts"] = rle["counts"].decode("ascii")
    return {"size": [int(v) for v in rle["size"]], "counts": rle["counts"]}, bbox, area


def yolo_lines(bboxes_coco: NDArray, class_ids: NDArray, width_px: int, height_px: int) -> str:
    """YOLO label text for COCO boxes (N, 4) and 0-based class ids (N,)."""
    lines = []
    for (x, y, w, h), c in zip(np.asarray(bboxes_coco, dtype=np.float64).reshape(-1, 4), class_ids):
        lines.append(f"{int(c)} {(x + 0.5 * w) / width_px:.6f} {(y + 0.5 * h) / height_px:.6f} "
                     f"{w / width_px:.6f} {h / height_px:.6f}")
    return "\n".join(lines) + ("\n" if lines else "")


def write_atomic(path: Path, data: bytes | str) -> None:
    """Write ``data`` to ``path`` via a temporary file and rename (no torn files)."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(data.encode() if isinstance(data, str) else data)
    os.replace(tmp, path)


def write_png_atomic(path: Path, image: NDArray[np.uint8]) -> None:
    """Encode ``image`` (H, W) uint8 as PNG and write it atomically.

    Raises:
        RuntimeError: OpenCV could not encode the image.
    """
    import cv2

    ok, png = cv2.imencode(".png", image)
    if not ok:
        raise RuntimeError(f"PNG encoding failed for {path}")
    write_atomic(path, png.tobytes())


def write_coco(path: Path, images: list[dict], annotations: list[dict], categories: list[dict],
               info: dict) -> None:
    """Write a COCO detection file (ids made consistent by the caller)."""
    doc = {"info": info, "licenses": [], "images": images, "annotations": annotations,
           "categories": categories}
    write_atomic(Path(path), json.dumps(doc, separators=(",", ":")))
