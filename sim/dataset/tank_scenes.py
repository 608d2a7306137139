"""Water-tank scenes matched to a real forward-looking sonar set, and their frames on its pixel grid.

The geometry is estimated from the real frames (``docs/studies/realism.md`` gives the estimate and
how it was made): the fan outline (:func:`sim.dataset.real_frames.fit_fan_outline`) gives
the near/far ratio of the window; the preset's minimum range (0.7 m for the ARIS 3000, its
nearest window start) gives the metric scale. The sonar looks down at a flat tank floor from
:data:`TANK.height_m` with its boresight tilted :data:`TANK.tilt_deg` down; a wall crosses the
far part of the fan in about half the scenes (the real set labels a wall in about half of
its frames); one to three debris objects of the real set's kinds, in its class mix, lie on
the floor in the fan.

Every scene is drawn from one seeded generator; frames are rendered with the project's
sonar (:class:`sim.sensors.fls.FlsSensor`) and resampled once from its polar image onto the
real set's fan pixels (:class:`sim.sensors.sonar.display.FanRemap` on the fitted geometry),
with the instance mask mapped to the real set's class ids.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from autonomy.sonar_geometry import FanGeometry
from sim.dataset.real_frames import MARINE_DEBRIS_CLASSES
from autonomy.frames import rot_from_euler
from sim.rng import component_rng
from sim.sensors.raycast import MujocoRayCaster
from sim.sensors.sonar.display import FanRemap

CLASS_ID = {name: cid for cid, name in MARINE_DEBRIS_CLASSES.items()}

#: Instances per class in the whole real set ([MarineDebrisFLS]): the scenes' class mix.
CLASS_MIX: dict[str, int] = {
    "Bottle": 468, "Can": 292, "Chain": 320, "Drink-carton": 347, "Hook": 171, "Propeller": 197,
    "Shampoo-bottle": 111, "Standing-bottle": 65, "Tire": 615, "Valve": 240}

#: Debris shape of each class (:mod:`sim.scene.debris_meshes`) and its pitch (deg) on the floor.
CLASS_SHAPE: dict[str, tuple[str, float]] = {
    "Bottle": ("bottle", 0.0), "Can": ("can", 0.0), "Chain": ("chain", 0.0), "Drink-carton": ("drink_carton", 0.0),
    "Hook": ("hook", 0.0), "Propeller": ("propeller", 0.0), "Shampoo-bottle": ("shampoo_bottle", 0.0),
    "Standing-bottle": ("bottle", 90.0), "Tire": ("tyre", 0.0), "Valve": ("valve", 0.0)}


@dataclass(frozen=True)
class TankGeometry:
    """Ranges of the drawn tank geometry (uniform between the bounds).

    Attributes:
        floor_depth_m: depth of the tank floor (the water surface is at 0), m.
        height_m: sonar head height above the floor, m.
        tilt_deg: boresight tilt below horizontal, deg.
        wall_share: share of scenes with a wall across the far fan.
        wall_range_m: slant range of the wall's nearest point on the boresight, m.
        objects: (min, max) debris objects per scene.
        object_range_m: ground range of the objects from the head, m.
        floor_reflectivity, wall_reflectivity: the floor's and wall's backscatter reflectivity.
        gain_jitter_db: standard deviation of a scene's display gain about the matched one, dB
            (the real frames' mid-range grey varies from frame to frame: recordings at
            different gains and poses).
    """

    floor_depth_m: float = 3.0
    height_m: tuple[float, float] = (0.25, 0.42)
    tilt_deg: tuple[float, float] = (12.0, 20.0)
    wall_share: float = 0.5
    wall_range_m: tuple[float, float] = (2.2, 3.2)
    objects: tuple[int, int] = (1, 3)
    object_range_m: tuple[float, float] = (1.0, 2.6)
    floor_reflectivity: float = 0.3
    wall_reflectivity: float = 0.6
    gain_jitter_db: float = 3.0


TANK = TankGeometry()

#: The image formation estimated for the ARIS 3000 in the tank (``docs/studies/realism.md``): FLS
#: config fields over the ``aris3000`` preset, estimated on the development frames.
#:
#: * TVG 40 log r, the point-target law (20 log r leaves the far range too dark against the
#:   real set's nearly flat range profile);
#: * a 12 mm pulse (four 3 mm bins): the real speckle's length along range;
#: * speckle correlated across the overlapping beams;
#: * a log-normal floor texture, sigma 0.7 over 2 cm;
#: * coherent object echoes (Rice factor 10) with an 8 cm echo tail of 0.3 of the echo;
#: * an amplitude display with gamma 0.5 through a soft limiter: the real grey histogram's
#:   bright tail, which thins out below 255 instead of piling up there;
#: * rays out to the vertical main lobe's first nulls (2.26 beam widths);
#: * an azimuth side-lobe plateau at -35 dB (two-way) out to 20 beam widths: bright echoes
#:   streak along the arc, as the real ones do.
TANK_FORMATION: dict = {
    "tvg_spreading_db_per_decade": 40.0,
    "side_lobe_extent_beamwidths": 20.0,
    "formation": {"pulse_length_m": 0.012, "beam_correlated_speckle": True, "texture_sigma": 0.7,
                  "texture_corr_m": 0.02, "display_gamma": 0.5, "display_soft_limit": True,
                  "elevation_span_beamwidths": 2.26, "object_tail_m": 0.08, "object_tail_ratio": 0.3,
                  "object_rice_k": 10.0, "side_lobe_floor_db": -35.0},
}


#: :data:`TANK_FORMATION` with objects as thin shells: a specular lobe on objects (0.6 of their
#: backscatter in ``cos^20``) and the far wall's echo (0.5 of the near wall's, one crossing
#: later), with the echo tail halved to 0.15 (the far wall now carries part of what the tail
#: stood for). Real bottles and cans show two or three parallel streaks along range, not a
#: filled outline (sim/sensors/sonar/image_formation.py; docs/studies/sim_to_real.md).
TANK_FORMATION_SHELLS: dict = {
    **TANK_FORMATION,
    "formation": {**TANK_FORMATION["formation"], "object_tail_ratio": 0.15, "object_specular_share": 0.6,
                  "object_specular_exponent": 20.0, "object_back_wall_ratio": 0.5, "object_back_wall_repeats": 1},
}

@dataclass(frozen=True)
class TankScene:
    """One drawn scene: the sonar pose and the world's targets (``TargetConfig`` list)."""

    index: int
    height_m: float
    tilt_deg: float
    yaw_deg: float
    targets: tuple
    gain_offset_db: float = 0.0


@dataclass(frozen=True)
class CatalogueEntry:
    """One kind of object a tank scene may hold.

    Attributes:
        class_name: its label.
        shape: a debris shape (:data:`sim.scene.debris_meshes.DEBRIS_SHAPES`) or ``tyre``.
        pitch_deg: its pitch on the floor (90: stood up on its base).
        weight: its share of the objects drawn (relative to the others').
        size_scale: (low, high) factor on its shape's default size, drawn uniformly per object.
    """

    class_name: str
    shape: str
    pitch_deg: float = 0.0
    weight: float = 1.0
    size_scale: tuple[float, float] = (0.85, 1.15)


#: The real set's objects: its classes, their shapes and their mix ([MarineDebrisFLS]).
MARINE_DEBRIS_CATALOGUE: tuple[CatalogueEntry, ...] = tuple(
    CatalogueEntry(name, CLASS_SHAPE[name][0], CLASS_SHAPE[name][1], float(CLASS_MIX[name])) for name in CLASS_MIX)


def draw_scene(index: int, rng: np.random.Generator, tank: TankGeometry = TANK,
               catalogue: tuple[CatalogueEntry, ...] = MARINE_DEBRIS_CATALOGUE) -> TankScene:
    """One scene drawn from ``rng``: the sonar's height and tilt, one to ``tank.objects``
    objects of ``catalogue`` (by weight; size scaled by the entry's ``size_scale``, any yaw, within +-11 deg of
    the boresight at ``tank.object_range_m``) and, in ``tank.wall_share`` of the scenes, a wall
    (class ``Wall``) across the far fan."""
    from scenarios.config.world import TargetConfig
    from sim.scene.debris_meshes import debris_default_size_m

    p = np.array([c.weight for c in catalogue], dtype=float)
    p /= p.sum()
    h = float(rng.uniform(*tank.height_m))
    tilt = float(rng.uniform(*tank.tilt_deg))
    targets = []
    floor = tank.floor_depth_m
    for j in range(int(rng.integers(tank.objects[0], tank.objects[1] + 1))):
        entry = catalogue[int(rng.choice(len(catalogue), p=p))]
        cls = entry.class_name
        rng_m = float(rng.uniform(*tank.object_range_m))
        az = float(rng.uniform(-11.0, 11.0))
        north, east = rng_m * np.cos(np.deg2rad(az)), rng_m * np.sin(np.deg2rad(az))
        yaw = float(rng.uniform(-180.0, 180.0))
        shape, pitch = entry.shape, entry.pitch_deg
        scale = float(rng.uniform(*entry.size_scale))
        if shape == "tyre":
            radius = 0.14 * scale
            targets.append(TargetConfig(name=f"obj{j}", shape="tyre", pos_ned=(north, east, floor),
                                        rpy_deg=(0.0, 0.0, yaw), radius_m=radius, tube_radius_m=0.35 * radius,
                                        reflectivity=0.9, class_name=cls, is_target=True))
            continue
        size = tuple(s * scale for s in debris_default_size_m(shape))
        # standing (pitched 90 deg): raised by half its length, so its base end is on the floor
        lift = 0.5 * size[0] if pitch else 0.0
        targets.append(TargetConfig(name=f"obj{j}", shape=shape, pos_ned=(north, east, floor - lift),
                                    rpy_deg=(0.0, pitch, yaw), size_m=size, reflectivity=0.9,
                                    class_name=cls, is_target=True))
    if rng.random() < tank.wall_share:
        wr = float(rng.uniform(*tank.wall_range_m))
        wyaw = float(rng.uniform(-35.0, 35.0))
        targets.append(TargetConfig(name="wall", shape="box", pos_ned=(wr + 0.15, 0.0, floor),
                                    rpy_deg=(0.0, 0.0, wyaw), size_m=(0.3, 8.0, floor), reflectivity=
                                    tank.wall_reflectivity, class_name="Wall", is_target=False))
    return TankScene(index, h, tilt, float(rng.uniform(-5.0, 5.0)), tuple(targets),
                     float(rng.normal(0.0, tank.gain_jitter_db)))


def draw_scenes(n: int, seed: int, tank: TankGeometry = TANK) -> list[TankScene]:
    """``n`` scenes drawn from one generator seeded with ``seed`` (:func:`draw_scene`)."""
    rng = np.random.default_rng(seed)
    return [draw_scene(i, rng, tank) for i in range(n)]


@dataclass(frozen=True)
class SimFrame:
    """A simulated frame on the real set's pixel grid: ``image`` (H, W) uint8, ``mask`` (H, W)
    uint8 real-set class ids (0 for a class it does not have), ``instances`` (H, W) int32 the
    scene object seen at each pixel (-1: none) and ``object_classes`` each object id's class."""

    scene: int
    image: NDArray[np.uint8]
    mask: NDArray[np.uint8]
    instances: NDArray[np.int32] | None = None
    object_classes: dict[int, str] | None = None


def render_tank_frames(scenes: list[TankScene], geom: FanGeometry, *, seed: int, frames_per_scene: int = 1,
                       fls_overrides: dict | None = None, tank: TankGeometry = TANK, preset: str = "aris3000",
                       rng: np.random.Generator | None = None, pose_rng: np.random.Generator | None = None
                       ) -> Iterator[SimFrame]:
    """Render each scene's frames with the ``preset`` sonar over ``geom``'s range window and
    resample them onto ``geom``'s pixels. ``fls_overrides``: further :class:`FlsConfig` fields
    (gain, noise floor, image formation). Speckle and noise from ``rng`` (default
    ``component_rng(seed, "fls")``), the frames' small pose changes from ``pose_rng`` (default
    ``component_rng(seed, "realism_poses")``)."""
    from scenarios.config.fls import FlsConfig
    from scenarios.config.world import SeabedConfig, WorldConfig
    from scenarios.schema import Scenario
    from sim.scene.world import build_world
    from sim.sensors.fls import FlsSensor

    rng = component_rng(seed, "fls") if rng is None else rng
    pose_rng = component_rng(seed, "realism_poses") if pose_rng is None else pose_rng
    remap = None
    over = dict(fls_overrides or {})
    base_gain_db = float(over.pop("gain_db", 0.0))
    for sc in scenes:
        cfg = FlsConfig(preset=preset, tilt_deg=sc.tilt_deg, rate_hz=1.0, gain_db=base_gain_db + sc.gain_offset_db,
                        range_window_m=(geom.range_min_m, min(geom.range_max_m, 5.0)), **over)
        sensor = FlsSensor(cfg, rng=rng)
        if remap is None:
            g = sensor.geometry
            remap = FanRemap(geom, g.beam_azimuths_rad(), g.window_near_m, g.range_resolution_m, g.n_bins)
        seabed = SeabedConfig(kind="plane", depth_m=tank.floor_depth_m, reflectivity=tank.floor_reflectivity,
                              extent_m=20.0)
        scenario = Scenario(name=f"tank_scene_{sc.index}", seed=seed + sc.index,
                            world=WorldConfig(seabed=seabed, targets=sc.targets))
        world = build_world(scenario, with_vehicle=False)
        caster = MujocoRayCaster(world.model, world.data, world.geom_object_id, world.geom_reflectivity,
                                 exclude_body_id=-1)
        class_of = np.zeros(len(world.objects) + 1, dtype=np.uint8)
        for obj in world.objects:
            class_of[int(obj.id)] = CLASS_ID.get(str(obj.class_name), 0)
        object_classes = {int(obj.id): str(obj.class_name) for obj in world.objects}
        for k in range(frames_per_scene):
            yaw = np.deg2rad(sc.yaw_deg + (pose_rng.uniform(-3.0, 3.0) if k else 0.0))
            pos = np.array([pose_rng.uniform(-0.05, 0.05) if k else 0.0, 0.0, tank.floor_depth_m - sc.height_m])
            render = sensor.render(float(k), pos, rot_from_euler(0.0, 0.0, yaw), caster, world.objects, truth=True)
            image = remap.image(render.frame.polar)
            ids = remap.labels(render.truth.mask_polar, -1)
            mask = np.where(ids >= 0, class_of[np.clip(ids, 0, len(class_of) - 1)], 0).astype(np.uint8)
            yield SimFrame(sc.index, image, mask, ids.astype(np.int32), object_classes)
