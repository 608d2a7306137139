"""Side-scan waterfall tiles with exact boxes, and their COCO / YOLO export.

A tile is ``pings_per_tile`` consecutive waterfall rows (along-track length
``pings_per_tile * speed / ping rate``) of the :class:`sim.sensors.sss.Waterfall` image
(port far range at column 0, starboard far range at the last column). Each object labelled
in a tile's bins (:attr:`sim.sensors.sss.SssRender.labels`, from the same rays as the
image) gets the box of its labelled pixels, with its class.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from sim.dataset.coco_io import write_atomic, write_coco, yolo_lines


@dataclass(frozen=True)
class SssTile:
    """One tile: ``image`` (n_pings, 2 n_bins) uint8, ``labels`` the same shape (object ids),
    ``boxes`` {object id: (x0, y0, x1, y1)} in pixels (x1, y1 exclusive), ``first_ping`` index."""

    image: NDArray[np.uint8]
    labels: NDArray[np.int16]
    boxes: dict[int, tuple[int, int, int, int]]
    first_ping: int


def pings_per_tile(tile_length_m: float, speed_mps: float, ping_rate_hz: float) -> int:
    """Pings in a tile of ``tile_length_m`` along track at ``speed_mps`` and ``ping_rate_hz``.

    Raises:
        ValueError: a non-positive length, speed or rate, or a tile shorter than one ping.
    """
    if not (tile_length_m > 0.0 and speed_mps > 0.0 and ping_rate_hz > 0.0):
        raise ValueError("tile_length_m, speed_mps and ping_rate_hz must be > 0")
    n = int(round(tile_length_m * ping_rate_hz / speed_mps))
    if n < 1:
        raise ValueError(f"a {tile_length_m} m tile holds no ping at {speed_mps} m/s and {ping_rate_hz} Hz")
    return n


def object_boxes(labels: NDArray[np.int16]) -> dict[int, tuple[int, int, int, int]]:
    """{object id: (x0, y0, x1, y1)} of each id >= 0 in a label image (x1, y1 exclusive)."""
    out = {}
    for k in np.unique(labels[labels >= 0]):
        rows, cols = np.nonzero(labels == k)
        out[int(k)] = (int(cols.min()), int(rows.min()), int(cols.max()) + 1, int(rows.max()) + 1)
    return out


def cut_tiles(image: NDArray[np.uint8], labels: NDArray[np.int16], n_pings: int) -> list[SssTile]:
    """Split a waterfall (n, W) and its labels into consecutive tiles of ``n_pings`` rows (the
    last, shorter part is dropped)."""
    tiles = []
    for start in range(0, image.shape[0] - n_pings + 1, n_pings):
        lab = labels[start:start + n_pings]
        tiles.append(SssTile(image[start:start + n_pings], lab, object_boxes(lab), start))
    return tiles


def write_tiles(out_dir: Path, tiles: list[SssTile], class_of: Mapping[int, str], categories: list[str]) -> Path:
    """Write tiles as PNGs with ``annotations.json`` (COCO) and ``labels/*.txt`` (YOLO).

    Args:
        out_dir: existing folder.
        tiles: the tiles.
        class_of: object id -> class name.
        categories: class names; COCO ids are 1-based in this order, YOLO ids 0-based.

    Returns:
        The COCO file.

    Raises:
        KeyError: an object's class is not in ``categories``.
    """
    out_dir = Path(out_dir)
    (out_dir / "images").mkdir(exist_ok=True)
    (out_dir / "labels").mkdir(exist_ok=True)
    cat_id = {name: i for i, name in enumerate(categories)}
    images, anns = [], []
    for i, t in enumerate(tiles):
        name = f"sss_{i:06d}.png"
        ok, png = cv2.imencode(".png", t.image)
        write_atomic(out_dir / "images" / name, png.tobytes())
        h, w = t.image.shape
        images.append({"id": i + 1, "file_name": f"images/{name}", "width": w, "height": h})
        ids = sorted(t.boxes)
        xyxy = np.array([t.boxes[k] for k in ids], dtype=float).reshape(-1, 4)
        coco = np.column_stack([xyxy[:, :2], xyxy[:, 2:] - xyxy[:, :2]])  # pixel k spans [k, k + 1)
        cls = np.array([cat_id[class_of[k]] for k in ids], dtype=int)
        for k, b, c in zip(ids, coco, cls):
            anns.append({"id": len(anns) + 1, "image_id": i + 1, "category_id": int(c) + 1,
                         "bbox": [float(v) for v in b], "area": float(b[2] * b[3]), "iscrowd": 0,
                         "object_id": int(k)})
        write_atomic(out_dir / "labels" / name.replace(".png", ".txt"), yolo_lines(coco, cls, w, h))
    path = out_dir / "annotations.json"
    write_coco(path, images, anns, [{"id": i + 1, "name": n} for i, n in enumerate(categories)],
               {"description": "auvsim side-scan tiles", "sensor": "sss"})
    write_atomic(out_dir / "categories.json", json.dumps(categories))
    return path
