"""Tank scenes of a dataset spec (``scene.kind: tank``) rendered as labelled frames on the
spec's fan pixel grid: the per-scene job of :func:`sim.dataset.generate.generate_dataset`.

Scene ``k`` of a dataset with root seed ``s`` is drawn from ``component_rng(s,
"dataset/tank/scene/k")`` (:func:`sim.dataset.tank_scenes.draw_scene`) and rendered with the
spec's sonar (speckle and noise from ``component_rng(s, "dataset/tank/fls/k")``, the small pose
changes between a scene's frames from ``component_rng(s, "dataset/tank/pose/k")``; the values
of the spec's ``sonar.randomize`` keys from ``component_rng(s, "dataset/tank/randomize/k")``,
recorded in each image's ``sonar.randomized``), resampled
onto the grid (:func:`sim.dataset.tank_scenes.render_tank_frames`): frames depend on (seed,
scene index) alone. Each object seen becomes a COCO annotation with its instance mask (RLE),
box and area; one of fewer than ``labels.min_area_px`` pixels is ``iscrowd``. With the
``watertank`` format each frame also gets its box file (``boxes/<id>.xml``, the objects not
``iscrowd``, ``x y w h`` px) and class mask (``masks/<id>.png``, category ids), the layout
:mod:`sim.dataset.labelled_folder` reads.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from sim.dataset.coco_io import IMAGES_DIR, fan_geometry_record, mask_annotation, write_atomic, write_png_atomic
from sim.dataset.spec import DatasetSpec
from sim.rng import component_rng

BOXES_DIR, MASKS_DIR = "boxes", "masks"


@dataclass(frozen=True)
class TankSettings:
    """What every frame of a tank dataset shares: its spec (as JSON, so a job pickles small)."""

    spec_json: str

    @cached_property
    def spec(self) -> DatasetSpec:
        return DatasetSpec.model_validate_json(self.spec_json)

    @property
    def frames_per_scene(self) -> int:
        return self.spec.scene.frames_per_scene

    @property
    def classes(self) -> tuple[str, ...]:
        return self.spec.scene.class_names()

    def __getstate__(self) -> dict:
        return {"spec_json": self.spec_json}  # not the cached model

    def __setstate__(self, state: dict) -> None:
        object.__setattr__(self, "spec_json", state["spec_json"])


def box_xml(boxes: list[tuple[str, list[float]]]) -> str:
    """A watertank box file: one ``object`` per (class, COCO ``[x, y, w, h]`` px)."""
    objs = "".join(f"  <object><name>{c}</name><bndbox><x>{int(round(b[0]))}</x><y>{int(round(b[1]))}</y>"
                   f"<w>{int(round(b[2]))}</w><h>{int(round(b[3]))}</h></bndbox></object>\n" for c, b in boxes)
    return f"<annotation>\n{objs}</annotation>\n"


def render_tank_scene(seed: int, index: int, settings: TankSettings, frame_ids: list[int], out_dir: Path) -> dict:
    """Render scene ``index``'s frames (ids ``frame_ids``), write their files; return the
    scene's label part (images and annotations, COCO records)."""
    from sim.dataset.tank_scenes import CatalogueEntry, TankGeometry, draw_scene, render_tank_frames

    spec = settings.spec
    sc = spec.scene
    tank = TankGeometry(floor_depth_m=sc.floor_depth_m, height_m=sc.height_m, tilt_deg=sc.tilt_deg,
                        wall_share=sc.wall_share, wall_range_m=sc.wall_range_m, objects=sc.objects,
                        object_range_m=sc.object_range_m, floor_reflectivity=sc.floor_reflectivity,
                        wall_reflectivity=sc.wall_reflectivity, gain_jitter_db=sc.gain_jitter_db)
    catalogue = tuple(CatalogueEntry(c.class_name, c.shape, c.pitch_deg, c.weight, tuple(c.size_scale))
                      for c in sc.catalogue)
    scene = draw_scene(index, component_rng(seed, f"dataset/tank/scene/{index}"), tank, catalogue)
    geom = spec.image.geometry()
    drawn = spec.sonar.draw(component_rng(seed, f"dataset/tank/randomize/{index}"))
    over = {k: v for k, v in spec.sonar.fls_fields(drawn).items() if k != "preset"}
    frames = render_tank_frames([scene], geom, seed=seed, frames_per_scene=len(frame_ids), fls_overrides=over,
                                tank=tank, preset=spec.sonar.preset,
                                rng=component_rng(seed, f"dataset/tank/fls/{index}"),
                                pose_rng=component_rng(seed, f"dataset/tank/pose/{index}"))
    cat_of = {name: k + 1 for k, name in enumerate(settings.classes)}
    watertank = "watertank" in spec.formats
    images, annotations = [], []
    for frame_id, frame in zip(frame_ids, frames):
        name = f"{IMAGES_DIR}/{frame_id:06d}.png"
        write_png_atomic(out_dir / name, frame.image)
        images.append({
            "id": frame_id, "file_name": name, "width": geom.width_px, "height": geom.height_px, "scene": index,
            "t_s": 0.0,
            "fan_geometry": fan_geometry_record(geom),
            "sonar": {"preset": spec.sonar.preset, "height_m": scene.height_m, "tilt_deg": scene.tilt_deg,
                      "yaw_deg": scene.yaw_deg, "gain_offset_db": scene.gain_offset_db,
                      **({"randomized": drawn} if drawn else {})},
        })
        class_mask = np.zeros(frame.image.shape, np.uint8)
        boxes = []
        for oid in sorted(int(i) for i in np.unique(frame.instances) if i >= 0):
            cls = frame.object_classes.get(oid)
            if cls not in cat_of:
                continue
            m = frame.instances == oid
            rle, bbox, area = mask_annotation(m)
            class_mask[m] = cat_of[cls]
            crowd = area < spec.labels.min_area_px
            x, y, w, h = bbox
            cx, cy = x + 0.5 * w - 0.5, y + 0.5 * h - 0.5
            annotations.append({
                "image_id": frame_id, "category_id": cat_of[cls], "bbox": bbox, "area": area, "segmentation": rle,
                "iscrowd": int(crowd),
                "attributes": {"object": f"{oid:04d}", "class_name": cls,
                               "range_m": math.hypot(cx - geom.apex_x_px, cy - geom.apex_y_px) * geom.m_per_px},
            })
            if not crowd:
                boxes.append((cls, bbox))
        if watertank:
            write_png_atomic(out_dir / MASKS_DIR / f"{frame_id:06d}.png", class_mask)
            write_atomic(out_dir / BOXES_DIR / f"{frame_id:06d}.xml", box_xml(boxes))
    return {"scene": index, "images": images, "annotations": annotations}
