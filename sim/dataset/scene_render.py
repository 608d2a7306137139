"""Render the frames of one dataset scene with the MuJoCo world and the FLS sensor."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from autonomy.frames import rot_from_euler
from autonomy.sonar_geometry import FanGeometry
from scenarios.config.fls import FlsConfig
from sim.dataset.coco_io import mask_annotation
from sim.dataset.randomization import SceneSpec


@dataclass(frozen=True)
class ObjectLabel:
    """One object's label in one frame; box and area from its fan-image instance mask."""

    name: str
    class_name: str
    shape: str
    is_target: bool
    visible_fraction: float
    bbox_coco: list[float]
    area_px: float
    rle: dict
    range_m: float
    azimuth_rad: float
    pos_ned: tuple[float, float, float]


@dataclass(frozen=True)
class FrameRecord:
    t_s: float
    fan: NDArray[np.uint8]
    geometry: FanGeometry
    pos_ned: tuple[float, float, float]
    rpy_rad: tuple[float, float, float]
    altitude_m: float
    objects: tuple[ObjectLabel, ...]


def render_frames(spec: SceneSpec, fls_cfg: FlsConfig, rng: np.random.Generator, n_frames: int) -> list[FrameRecord]:
    """Build ``spec``'s world and render its first ``n_frames`` poses (noise drawn from ``rng``)."""
    from scenarios.config.world import WorldConfig
    from scenarios.schema import Scenario
    from sim.sensors.fls import FlsSensor
    from sim.sensors.raycast import MujocoRayCaster
    from sim.scene.world import build_world

    scenario = Scenario(name=f"dataset_scene_{spec.index}", seed=spec.world_seed,
                        world=WorldConfig(seabed=spec.seabed, basin=spec.basin, targets=spec.targets))
    world = build_world(scenario, with_vehicle=False)
    caster = MujocoRayCaster(world.model, world.data, world.geom_object_id, world.geom_reflectivity,
                             exclude_body_id=-1)
    sensor = FlsSensor(fls_cfg, rng=rng)
    shape_of = {t.name: t.shape for t in spec.targets}
    out = []
    for j, pose in enumerate(spec.poses[:n_frames]):
        t_s = float(j)
        R_nb = rot_from_euler(*pose.rpy_rad)
        render = sensor.render(t_s, np.array(pose.pos_ned), R_nb, caster, world.objects, noise=True)
        labels = []
        # column-major once per frame: each object's mask then reaches the RLE encoder without a copy
        mask_fan = np.asfortranarray(render.truth.mask_fan)
        for obj in render.truth.objects:
            m = mask_fan == obj.id
            if not m.any():
                continue
            rle, bbox, area = mask_annotation(m)
            frac = float(obj.visible_fraction) if np.isfinite(obj.visible_fraction) else 1.0
            labels.append(ObjectLabel(
                name=obj.name, class_name=obj.class_name, shape=shape_of[obj.name], is_target=obj.is_target,
                visible_fraction=frac, bbox_coco=bbox, area_px=area, rle=rle, range_m=float(obj.range_m),
                azimuth_rad=float(obj.azimuth_rad), pos_ned=tuple(float(v) for v in obj.pos_ned)))
        altitude = float(world.seabed.depth_at(pose.pos_ned[0], pose.pos_ned[1])) - pose.pos_ned[2]
        out.append(FrameRecord(t_s, render.frame.fan, render.frame.geometry, pose.pos_ned, pose.rpy_rad,
                               altitude, tuple(labels)))
    return out
