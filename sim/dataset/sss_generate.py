"""``auvsim dataset --sensor sss``: side-scan waterfall tiles with exact boxes.

Per scene, a straight, level survey line over a randomised seabed with objects scattered on
both sides: the side-scan sonar (:class:`sim.sensors.sss.SssSensor`) pings along it at
its ping rate, the pings form a waterfall (one row per ping, port far range at column 0,
starboard far range at the last column; slant range), and the waterfall is cut into tiles of
``tile_length_m`` along track. Each object labelled in a tile's bins (the same rays as the
image) gets the box of its labelled pixels, with its class.

The layout is the FLS dataset's (:mod:`sim.dataset.generate`): ``manifest.json`` (with
``"sensor": "sss"``), ``images/000001.png`` (one per tile, (pings, 2 n_bins) 8-bit grey),
``parts/scene_00000.json``, ``annotations.json`` (COCO boxes, no masks) and
``labels/000001.txt`` (YOLO). Tiles depend only on (seed, scene index).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from pydantic import model_validator

from scenarios.config.world import SeabedConfig, TargetConfig
from sim.dataset.coco_io import IMAGES_DIR, write_png_atomic
from sim.dataset.errors import DatasetError
from sim.dataset.randomization import CLASS_NAMES, Range, Randomization, SceneRanges, _object, _u, seabed_depth_fn
from sim.rng import component_rng

#: Side-scan altitude over the seabed as a fraction of the slant range per side: the usual
#: survey practice (the ``mcm_survey_full`` scenario flies 8 m with a 75 m range, 11 %). Much
#: lower, the far seabed is met at a grazing angle whose Lambert backscatter falls below the
#: display's dynamic range (a black far field, where objects cast no visible shadow); much
#: higher, the nadir gap (the water column, one altitude of slant range) eats the swath.
ALTITUDE_FRACTION_OF_RANGE: tuple[float, float] = (0.10, 0.20)
#: The transducer stays at least this deep (the seabed range is raised to fit), m.
MIN_TRANSDUCER_DEPTH_M = 2.0


@dataclass(frozen=True)
class SssSettings:
    """Side-scan dataset settings common to all scenes (the rest is randomised per scene).

    ``line_length_m``: survey line per scene, m; ``tile_length_m``: along-track length of a
    tile, m (``line_length_m // tile_length_m`` tiles per scene); ``speed_mps``: speed over
    ground along the line; ``range_max_m``, ``n_bins``, ``elevation_rays``: the sonar's slant
    range per side, bins per side and rays per side; ``rate_hz`` None: the two-way travel-time
    limit ``1500 / (2 range_max_m)``; ``gain_db``: display gain of the tiles, dB, before each
    scene's random offset (``randomization.gain_db``): -10 dB, the ``mcm_survey_full``
    scenario's, lifts the far-range seabed above the display floor (the side-scan's default
    -25 dB leaves a Lambert seabed black over much of the far range, where far objects'
    shadows cannot show).
    """

    line_length_m: float = 150.0
    tile_length_m: float = 50.0
    speed_mps: float = 2.0
    range_max_m: float = 40.0
    n_bins: int = 500
    elevation_rays: int = 32
    rate_hz: float | None = None
    gain_db: float = -10.0

    def check(self) -> None:
        """Raises DatasetError naming the option that is out of range."""
        if not (self.tile_length_m > 0 and math.isfinite(self.tile_length_m)):
            raise DatasetError(f"--tile-length: must be a positive number of metres, got {self.tile_length_m}")
        if not (self.line_length_m > 0 and math.isfinite(self.line_length_m)):
            raise DatasetError(f"--line-length: must be a positive number of metres, got {self.line_length_m}")
        if self.tile_length_m > self.line_length_m:
            raise DatasetError(f"--tile-length {self.tile_length_m:g} m: longer than the survey line "
                               f"(--line-length {self.line_length_m:g} m); give a tile length <= the line length")
        if self.pings_per_tile() < 2:
            raise DatasetError(f"--tile-length {self.tile_length_m:g} m: holds fewer than 2 pings at "
                               f"{self.speed_mps:g} m/s and {self.ping_rate_hz():.3g} Hz")

    def ping_rate_hz(self) -> float:
        return float(self.rate_hz) if self.rate_hz is not None else 1500.0 / (2.0 * self.range_max_m)

    def pings_per_tile(self) -> int:
        """Pings per tile: ``round(tile_length_m * rate / speed)``."""
        return int(round(self.tile_length_m * self.ping_rate_hz() / self.speed_mps))

    def tiles_per_scene(self) -> int:
        return int(self.line_length_m // self.tile_length_m)


class SssRandomization(SceneRanges):
    """Uniform ranges ``(low, high)`` a side-scan scene is drawn from: the part of
    :class:`sim.dataset.randomization.Randomization` a side-scan line uses, with a side-scan
    altitude. This, not the FLS ranges it may be made from, is what a side-scan dataset's
    ``manifest.json`` records (``randomization``).

    ``seabed_kinds`` without ``slope`` (the line is level); ``altitude_m`` of the transducer
    over the seabed at the line's ends, m; ``n_targets`` / ``n_distractors`` per tile; the
    object fields as in ``Randomization``. The defaults are the ``train`` preset's for the
    default 40 m range (:func:`sss_randomization`).
    """

    seabed_kinds: tuple[str, ...] = ("plane", "rough", "ripple")
    seabed_depth_m: Range = (10.0, 20.0)
    altitude_m: Range = (4.0, 8.0)

    @model_validator(mode="after")
    def _ranges(self) -> "SssRandomization":
        bad = set(self.seabed_kinds) - {"plane", "rough", "ripple"}
        if bad or not self.seabed_kinds:
            raise ValueError(f"seabed_kinds: {sorted(bad) or 'none'} not allowed; a side-scan line takes plane, "
                             "rough, ripple")
        if not self.altitude_m[0] > 0.0:
            raise ValueError(f"altitude_m: must be above 0 m, got {self.altitude_m}")
        return self


def sss_randomization(rz: Randomization | SssRandomization, settings: SssSettings) -> SssRandomization:
    """The side-scan ranges of a dataset made with ``rz``: an :class:`SssRandomization` as is;
    an FLS :class:`~sim.dataset.randomization.Randomization` (the CLI's presets) keeps its
    seabed, echo and object ranges, drops ``slope`` from the seabed kinds, and takes the
    side-scan altitude :data:`ALTITUDE_FRACTION_OF_RANGE` of ``settings.range_max_m`` in place
    of its FLS altitudes, with the seabed depth raised to keep the transducer
    :data:`MIN_TRANSDUCER_DEPTH_M` deep."""
    if isinstance(rz, SssRandomization):
        return rz
    r = settings.range_max_m
    altitude = (ALTITUDE_FRACTION_OF_RANGE[0] * r, ALTITUDE_FRACTION_OF_RANGE[1] * r)
    floor = altitude[1] + MIN_TRANSDUCER_DEPTH_M
    depth = (max(rz.seabed_depth_m[0], floor), max(rz.seabed_depth_m[1], floor))
    kinds = tuple(k for k in rz.seabed_kinds if k != "slope") or ("plane",)
    shared = {k: getattr(rz, k) for k in SceneRanges.model_fields}
    return SssRandomization(seabed_kinds=kinds, seabed_depth_m=depth, altitude_m=altitude, **shared)


@dataclass(frozen=True)
class SssSceneSpec:
    """One side-scan scene: seabed, objects and the survey line.

    ``start_ned``: (3,) transducer position at the first ping, NED m; ``heading_rad``: line
    heading (yaw, from north towards east); ``end_depth_m``: transducer depth at the end of
    the line (depth varies linearly along the line, so it follows a sloping bed in a straight
    line); the rest as in :class:`sim.dataset.randomization.SceneSpec`.
    """

    index: int
    world_seed: int
    seabed: SeabedConfig
    targets: tuple[TargetConfig, ...]
    start_ned: tuple[float, float, float]
    end_depth_m: float
    heading_rad: float
    altitude_m: float
    gain_db: float
    noise_scale: float
    speckle: str
    k_shape: float


def track(spec: SssSceneSpec, settings: SssSettings, n_pings: int) -> NDArray[np.float64]:
    """(n_pings, 3) transducer positions (NED m) of pings 0..n_pings-1 along the line:
    ping k at along-track distance ``k speed / rate``."""
    step = settings.speed_mps / settings.ping_rate_hz()
    s = np.arange(n_pings) * step
    h = np.array([math.cos(spec.heading_rad), math.sin(spec.heading_rad)])
    p = np.zeros((n_pings, 3))
    p[:, :2] = np.asarray(spec.start_ned[:2]) + s[:, None] * h
    p[:, 2] = spec.start_ned[2] + (spec.end_depth_m - spec.start_ned[2]) * s / settings.line_length_m
    return p


def sample_sss_scene(index: int, rng: np.random.Generator, rz: SssRandomization, settings: SssSettings,
                     seabed_depth_fn) -> SssSceneSpec:
    """Draw side-scan scene ``index``: a line of ``settings.line_length_m`` centred on the
    origin at a random heading, altitude from ``rz.altitude_m`` (at the line's ends), and
    ``rz.n_targets`` + ``rz.n_distractors`` (per tile) objects at random along-track
    positions and ground ranges between twice the altitude and 90 % of the swath, either side."""
    world_seed = int(rng.integers(0, 2**31 - 1))
    kind = str(rng.choice(rz.seabed_kinds))
    L, R = settings.line_length_m, settings.range_max_m
    seabed = SeabedConfig(
        kind=kind, depth_m=_u(rng, rz.seabed_depth_m), roughness_m=_u(rng, rz.roughness_m),
        roughness_corr_m=_u(rng, rz.roughness_corr_m), ripple_amplitude_m=_u(rng, rz.ripple_amplitude_m),
        ripple_wavelength_m=_u(rng, rz.ripple_wavelength_m), ripple_azimuth_deg=_u(rng, (-180.0, 180.0)),
        extent_m=float(np.ceil(L + 2.0 * R + 10.0)), mesh_resolution_m=0.5,
        reflectivity=_u(rng, rz.seabed_reflectivity))
    depth = seabed_depth_fn(seabed, world_seed)
    yaw = _u(rng, (-np.pi, np.pi))
    h = np.array([np.cos(yaw), np.sin(yaw)])
    right = np.array([-h[1], h[0]])  # starboard
    altitude = _u(rng, rz.altitude_m)
    a, b = -0.5 * L * h, 0.5 * L * h
    z0 = float(depth(a[0], a[1])) - altitude
    z1 = float(depth(b[0], b[1])) - altitude
    n_tiles = settings.tiles_per_scene()
    objects: list[TargetConfig] = []
    g_lo, g_hi = 2.0 * altitude + 1.0, 0.9 * R
    for tile in range(n_tiles):
        n_t = int(rng.integers(rz.n_targets[0], rz.n_targets[1] + 1))
        n_d = int(rng.integers(rz.n_distractors[0], rz.n_distractors[1] + 1))
        for k in range(n_t + n_d):
            is_target = k < n_t
            s = -0.5 * L + settings.tile_length_m * (tile + _u(rng, (0.1, 0.9)))
            g = _u(rng, (g_lo, max(g_lo, g_hi))) * (1.0 if rng.random() < 0.5 else -1.0)
            prefix = "t" if is_target else "d"
            objects.append(_object(rng, f"{prefix}{len(objects)}", s * h + g * right, depth, rz, is_target))
    return SssSceneSpec(index=index, world_seed=world_seed, seabed=seabed, targets=tuple(objects),
                        start_ned=(float(a[0]), float(a[1]), z0), end_depth_m=z1, heading_rad=float(yaw),
                        altitude_m=altitude, gain_db=_u(rng, rz.gain_db), noise_scale=_u(rng, rz.noise_scale),
                        speckle="k" if rng.random() < rz.k_speckle_probability else "rayleigh",
                        k_shape=_u(rng, rz.k_shape))


def sss_scene_spec(seed: int, index: int, rz: Randomization | SssRandomization,
                   settings: SssSettings) -> SssSceneSpec:
    """The scene ``index`` of a side-scan dataset with root ``seed`` and ranges
    :func:`sss_randomization` ``(rz, settings)`` (depends on nothing else)."""

    return sample_sss_scene(index, component_rng(seed, f"dataset/sss_scene/{index}"),
                            sss_randomization(rz, settings), settings, seabed_depth_fn)


def sss_config(spec: SssSceneSpec, settings: SssSettings):
    from scenarios.config.sss import SssConfig

    base = SssConfig()
    kw = dict(range_max_m=settings.range_max_m, n_bins=settings.n_bins, elevation_rays=settings.elevation_rays,
              gain_db=settings.gain_db + spec.gain_db,
              noise_floor_db=base.noise_floor_db + 10.0 * math.log10(spec.noise_scale),
              speckle=spec.speckle, k_shape=spec.k_shape, mount_pos_body_m=(0.0, 0.0, 0.0))
    if settings.rate_hz is not None:
        kw["rate_hz"] = settings.rate_hz
    return SssConfig(**kw)


def render_sss_scene(spec: SssSceneSpec, seed: int, settings: SssSettings, tile_ids: list[int],
                     out_dir: Path) -> dict:
    """Ping along the scene's line, cut the waterfall into tiles, write the first
    ``len(tile_ids)`` tiles' PNGs; return the scene's label part (COCO images/annotations)."""
    from autonomy.frames import rot_from_euler
    from scenarios.config.world import WorldConfig
    from scenarios.schema import Scenario
    from sim.sensors.raycast import MujocoRayCaster
    from sim.sensors.sss import SssSensor, Waterfall
    from sim.dataset.sss_tiles import cut_tiles
    from sim.scene.world import build_world

    scenario = Scenario(name=f"dataset_sss_scene_{spec.index}", seed=spec.world_seed,
                        world=WorldConfig(seabed=spec.seabed, targets=spec.targets))
    world = build_world(scenario, with_vehicle=False)
    caster = MujocoRayCaster(world.model, world.data, world.geom_object_id, world.geom_reflectivity,
                             exclude_body_id=-1)
    sonar = SssSensor(sss_config(spec, settings), rng=component_rng(seed, f"dataset/sss/{spec.index}"))
    ppt = settings.pings_per_tile()
    n_pings = ppt * len(tile_ids)
    positions = track(spec, settings, n_pings)
    R_nb = rot_from_euler(0.0, 0.0, spec.heading_rad)
    rate = settings.ping_rate_hz()
    wf = Waterfall(sonar.n_bins)
    for k, p in enumerate(positions):
        wf.add(sonar.render(k / rate, p, R_nb, caster, world.objects, noise=True))
    tiles = cut_tiles(wf.image(), wf.labels(), ppt)
    by_id = {o.id: o for o in world.objects}
    images, annotations = [], []
    for tile_id, tile in zip(tile_ids, tiles):
        name = f"{IMAGES_DIR}/{tile_id:06d}.png"
        write_png_atomic(out_dir / name, tile.image)
        h_px, w_px = tile.image.shape
        first = positions[tile.first_ping]
        images.append({
            "id": tile_id, "file_name": name, "width": int(w_px), "height": int(h_px), "scene": spec.index,
            "t_s": tile.first_ping / rate, "first_ping": int(tile.first_ping),
            "sss_geometry": {"n_bins": sonar.n_bins, "bin_size_m": sonar.bin_size_m, "range_max_m": settings.range_max_m,
                             "ping_rate_hz": rate, "speed_mps": settings.speed_mps,
                             "along_track_m_per_px": settings.speed_mps / rate,
                             "columns": "port far range at 0, starboard far range at width - 1 (slant range)"},
            "sonar": {"first_pos_ned": [float(v) for v in first], "heading_rad": spec.heading_rad,
                      "end_depth_m": spec.end_depth_m, "line_start_ned": list(spec.start_ned),
                      "line_length_m": settings.line_length_m, "altitude_m": spec.altitude_m,
                      "seabed": spec.seabed.kind, "gain_db": spec.gain_db, "noise_scale": spec.noise_scale,
                      "speckle": spec.speckle},
        })
        for oid in sorted(tile.boxes):
            x0, y0, x1, y1 = tile.boxes[oid]
            obj = by_id[oid]
            annotations.append({
                "image_id": tile_id, "category_id": CLASS_NAMES.index(obj.class_name) + 1,
                "bbox": [float(x0), float(y0), float(x1 - x0), float(y1 - y0)],
                "area": float(np.count_nonzero(tile.labels == oid)), "iscrowd": 0,
                "attributes": {"object": obj.name, "object_id": int(oid), "shape": obj.shape,
                               "is_target": obj.is_target, "base_ned": [float(v) for v in obj.base_ned]},
            })
    return {"scene": spec.index, "images": images, "annotations": annotations}
