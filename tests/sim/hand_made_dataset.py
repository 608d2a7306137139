"""A few hand-made FLS dataset folders (COCO file + PNG fans) for the commands that read
datasets: fans of a chosen size, plain grey with a labelled box each, written in milliseconds
instead of rendered."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np

from autonomy.sonar_geometry import FanGeometry

CLASSES = ("opi", "rock", "debris")


def write_fan_dataset(folder: Path, n_images: int = 4, fan_hw: tuple[int, int] = (477, 894),
                      labelled: tuple[str, ...] = ("opi", "rock"), grey: int = 40) -> Path:
    """``n_images`` uniform ``grey`` fans of ``fan_hw`` (height, width), each with one labelled
    box per class in ``labelled`` (nothing drawn there); categories: :data:`CLASSES`."""
    (folder / "images").mkdir(parents=True)
    h, w = fan_hw
    g = FanGeometry.fit(w, h, 1.0, 30.0, np.deg2rad(130.0))
    images, anns = [], []
    for i in range(n_images):
        name = f"images/{i:06d}.png"
        cv2.imwrite(str(folder / name), np.full((h, w), grey, np.uint8))
        images.append({"id": i, "file_name": name, "width": w, "height": h, "t_s": 0.0,
                       "fan_geometry": {"width_px": g.width_px, "height_px": g.height_px, "range_min_m": g.range_min_m,
                                        "range_max_m": g.range_max_m, "fov_rad": g.fov_rad, "m_per_px": g.m_per_px,
                                        "apex_x_px": g.apex_x_px, "apex_y_px": g.apex_y_px}})
        for k, cls in enumerate(labelled):
            x, y = 0.3 * w + 0.2 * w * k, 0.4 * h
            anns.append({"id": len(anns) + 1, "image_id": i, "category_id": CLASSES.index(cls) + 1,
                         "bbox": [x, y, 0.05 * w, 0.05 * h], "area": 0.0025 * w * h, "iscrowd": 0,
                         "attributes": {"range_m": 15.0}})
    cats = [{"id": k + 1, "name": n} for k, n in enumerate(CLASSES)]
    (folder / "annotations.json").write_text(json.dumps({"images": images, "annotations": anns, "categories": cats}))
    return folder
