"""Domain-randomisation ranges and the sampling of one dataset scene (numpy; object meshes
from :mod:`sim.scene.target_meshes` to rest each object on the seabed)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from autonomy.frames import rot_from_euler
from scenarios.config.base import StrictModel
from scenarios.config.world import BasinConfig, SeabedConfig, TargetConfig
from sim.rng import component_rng
from sim.scene.seabed import make_seabed

#: The labelled classes of the FLS datasets, in COCO category order (id = index + 1).
CLASS_NAMES = ("opi", "rock", "debris")


def seabed_depth_fn(seabed_cfg: SeabedConfig, world_seed: int):
    """``depth_at(n_m, e_m)`` of the seabed ``seabed_cfg`` drawn from ``world_seed`` (m, NED)."""
    bed = make_seabed(seabed_cfg, component_rng(world_seed, "seabed"))
    return bed.depth_at

Range = tuple[float, float]
TARGET_CLASS = "opi"


def _check_range(name: str, r: Range) -> None:
    if r[0] > r[1]:
        raise ValueError(f"{name}: lower bound {r[0]} above upper bound {r[1]}")


class BasinRandomization(StrictModel):
    """Rectangular basin walls as background clutter: with ``probability`` a scene gets an
    axis-aligned basin whose wall faced by the sonar lies ``wall_range_m`` ahead of the first
    pose (slant along the heading); half sizes from ``half_size_m``."""

    probability: float = Field(0.3, ge=0.0, le=1.0)
    wall_range_m: Range = (4.0, 40.0)
    half_size_m: Range = (12.0, 50.0)
    reflectivity: Range = (0.4, 0.9)


class SceneRanges(StrictModel):
    """The ranges ``(low, high)`` a forward-looking and a side-scan scene share: seabed texture,
    echo level and noise, and the objects (count, shape, size, reflectivity, burial). Every
    two-number range must have its lower bound first."""

    seabed_reflectivity: Range = (0.15, 0.5)
    roughness_m: Range = (0.02, 0.15)
    roughness_corr_m: Range = (1.0, 4.0)
    ripple_amplitude_m: Range = (0.02, 0.12)
    ripple_wavelength_m: Range = (0.8, 3.5)
    gain_db: Range = (-4.0, 4.0)
    noise_scale: Range = (0.5, 2.0)
    k_speckle_probability: float = Field(0.3, ge=0.0, le=1.0)
    k_shape: Range = (1.5, 10.0)
    n_targets: tuple[int, int] = (0, 4)
    n_distractors: tuple[int, int] = (0, 4)
    burial_fraction: Range = (0.0, 0.5)
    burial_probability: float = Field(0.3, ge=0.0, le=1.0)
    target_shapes: tuple[str, ...] = ("half_sphere", "truncated_cone", "cylinder", "box", "tyre")
    target_size_m: Range = (0.4, 1.2)
    target_reflectivity: Range = (0.6, 1.0)
    distractor_size_m: Range = (0.2, 1.0)
    distractor_reflectivity: Range = (0.15, 0.45)

    @model_validator(mode="after")
    def _ordered_ranges(self) -> "SceneRanges":
        for name, value in self:
            if isinstance(value, tuple) and len(value) == 2 and all(isinstance(v, (int, float)) for v in value):
                _check_range(name, value)
        return self


class Randomization(SceneRanges):
    """Uniform ranges ``(low, high)`` every scene parameter is drawn from (the shared ones in
    :class:`SceneRanges`).

    Targets (``class_name`` ``opi``) are the five mine-like shapes; distractors are rocks
    (tumbled boxes, flattened half spheres) and debris (thin lying cylinders), never targets.
    """

    seabed_kinds: tuple[str, ...] = ("plane", "slope", "rough", "ripple")
    seabed_depth_m: Range = (8.0, 20.0)
    slope_deg: Range = (1.0, 10.0)
    altitude_m: Range = (1.5, 6.0)
    tilt_deg: Range = (3.0, 14.0)
    vertical_beamwidth_deg: float = Field(20.0, gt=0.0, le=90.0, description="to place objects on insonified bed")
    roll_pitch_jitter_deg: float = Field(3.0, ge=0.0, le=20.0)
    range_max_m: Range = (15.0, 35.0)
    range_min_m: Range = (1.0, 2.0)
    cluster_probability: float = Field(0.3, ge=0.0, le=1.0)
    cluster_spacing_m: Range = (1.0, 3.0)
    frames_per_scene: int = Field(4, ge=1, le=100)
    step_m: Range = (1.0, 4.0)
    basin: BasinRandomization | None = Field(None, description="basin walls as background (None: never)")

    @model_validator(mode="after")
    def _ranges(self) -> "Randomization":
        bad = set(self.seabed_kinds) - {"plane", "slope", "rough", "ripple"}
        if bad:
            raise ValueError(f"seabed_kinds: unknown {sorted(bad)}, allowed plane, slope, rough, ripple")
        bad = set(self.target_shapes) - {"half_sphere", "truncated_cone", "cylinder", "box", "tyre"}
        if bad:
            raise ValueError(f"target_shapes: unknown {sorted(bad)}")
        return self


TRAIN_RANDOMIZATION = Randomization()
# Wider training ranges (model v2): covers higher altitudes, rougher/longer-rippled beds, more
# noise and heavy-tailed clutter, darker targets, more distractors and basin walls as background.
WIDE_RANDOMIZATION = Randomization(
    seabed_reflectivity=(0.15, 0.55), slope_deg=(1.0, 12.0), roughness_m=(0.02, 0.2),
    ripple_amplitude_m=(0.02, 0.15), ripple_wavelength_m=(0.8, 4.5), altitude_m=(1.5, 7.0),
    noise_scale=(0.5, 2.5), k_speckle_probability=0.45, k_shape=(1.0, 10.0),
    target_reflectivity=(0.5, 1.0), n_distractors=(0, 6), basin=BasinRandomization(),
)
# Held-out set: other altitudes, rougher and differently rippled seabeds, more noise, darker targets.
HELDOUT_RANDOMIZATION = Randomization(
    seabed_depth_m=(10.0, 25.0), seabed_reflectivity=(0.35, 0.55), roughness_m=(0.12, 0.2),
    ripple_amplitude_m=(0.08, 0.15), ripple_wavelength_m=(3.0, 4.5), slope_deg=(8.0, 12.0),
    altitude_m=(5.5, 7.0), tilt_deg=(8.0, 14.0), noise_scale=(1.5, 2.2), target_reflectivity=(0.55, 0.85),
    k_speckle_probability=0.6, k_shape=(1.0, 2.5),
)

#: The named randomisation presets (``auvsim dataset --randomization``, a spec's ``randomization``).
RANDOMIZATION_PRESETS = {"train": TRAIN_RANDOMIZATION, "wide": WIDE_RANDOMIZATION, "heldout": HELDOUT_RANDOMIZATION}


@dataclass(frozen=True)
class ScenePose:
    """Sonar carrier pose of one frame: vehicle position NED and roll/pitch/yaw (rad)."""

    pos_ned: tuple[float, float, float]
    rpy_rad: tuple[float, float, float]


@dataclass(frozen=True)
class SceneSpec:
    """Everything needed to build and render one scene deterministically."""

    index: int
    world_seed: int
    seabed: SeabedConfig
    targets: tuple[TargetConfig, ...]
    poses: tuple[ScenePose, ...]
    tilt_rad: float
    range_min_m: float
    range_max_m: float
    gain_db: float
    noise_scale: float
    speckle: str
    k_shape: float
    basin: BasinConfig = BasinConfig()


def _u(rng: np.random.Generator, r: Range) -> float:
    return float(rng.uniform(r[0], r[1]))


def _object(rng: np.random.Generator, name: str, pos_ne: np.ndarray, seabed_depth, rz: Randomization,
            is_target: bool) -> TargetConfig:
    yaw = _u(rng, (-180.0, 180.0))
    if is_target:
        shape = str(rng.choice(rz.target_shapes))
        size = _u(rng, rz.target_size_m)
        refl = _u(rng, rz.target_reflectivity)
        kw: dict = dict(class_name=TARGET_CLASS, is_target=True)
        if shape == "half_sphere":
            kw.update(radius_m=0.5 * size)
            height = 0.5 * size
        elif shape == "truncated_cone":
            kw.update(radius_m=0.5 * size, top_radius_m=0.5 * size * _u(rng, (0.2, 0.6)),
                      height_m=size * _u(rng, (0.4, 0.8)))
            height = kw["height_m"]
        elif shape == "cylinder":
            kw.update(radius_m=0.5 * size * _u(rng, (0.4, 0.8)), height_m=size * _u(rng, (0.4, 1.0)))
            height = kw["height_m"]
        elif shape == "box":
            kw.update(size_m=(size, size * _u(rng, (0.4, 1.0)), size * _u(rng, (0.3, 0.6))))
            height = kw["size_m"][2]
        else:
            kw.update(radius_m=0.5 * size, tube_radius_m=0.5 * size * _u(rng, (0.2, 0.35)))
            height = 2 * kw["tube_radius_m"]
        rpy = (0.0, 0.0, yaw)
    else:
        refl = _u(rng, rz.distractor_reflectivity)
        size = _u(rng, rz.distractor_size_m)
        kind = str(rng.choice(["rock_box", "rock_dome", "debris"]))
        if kind == "rock_box":
            shape = "box"
            kw = dict(class_name="rock", is_target=False,
                      size_m=(size, size * _u(rng, (0.5, 1.0)), size * _u(rng, (0.3, 0.8))))
            rpy = (_u(rng, (-25.0, 25.0)), _u(rng, (-25.0, 25.0)), yaw)
            height = kw["size_m"][2]
        elif kind == "rock_dome":
            shape = "half_sphere"
            kw = dict(class_name="rock", is_target=False, radius_m=0.5 * size)
            rpy = (_u(rng, (-30.0, 30.0)), _u(rng, (-30.0, 30.0)), yaw)
            height = 0.5 * size
        else:
            shape = "cylinder"
            length = _u(rng, (1.0, 3.0))
            kw = dict(class_name="debris", is_target=False, radius_m=_u(rng, (0.03, 0.12)), height_m=length)
            rpy = (90.0, 0.0, yaw)  # lying on its side
            height = 2 * kw["radius_m"]
    burial = 0.0
    if rng.random() < rz.burial_probability:
        burial = _u(rng, rz.burial_fraction) * height
    at_origin = TargetConfig(name=name, shape=shape, pos_ned=(float(pos_ne[0]), float(pos_ne[1]), 0.0),
                             rpy_deg=rpy, reflectivity=refl, **kw)
    z = resting_depth(at_origin, seabed_depth) + burial
    return TargetConfig(**{**at_origin.model_dump(), "pos_ned": (float(pos_ne[0]), float(pos_ne[1]), z)})


def resting_depth(target: TargetConfig, seabed_depth) -> float:
    """Base depth (NED z, m) at which ``target``, posed at its north/east and attitude, rests on
    the seabed: its mesh touches the bed and nowhere goes below it.

    Args:
        target: the object (its ``pos_ned`` depth is ignored).
        seabed_depth: ``depth(n_m, e_m) -> z`` of the seabed, vectorised.

    Returns:
        ``min over mesh vertices v of (seabed depth under v - v_z)`` for the object posed with its
        base at depth 0: a lying cylinder's axis ends up one radius above a flat bed, a tilted
        rock's lowest corner on it.
    """
    from sim.scene.target_meshes import target_mesh

    R = rot_from_euler(*np.deg2rad(target.rpy_deg))
    v = target_mesh(target).vertices @ R.T
    v[:, :2] += np.asarray(target.pos_ned[:2], dtype=float)
    return float(np.min(np.asarray(seabed_depth(v[:, 0], v[:, 1]), dtype=float) - v[:, 2]))


def draw_world_seed_and_seabed_kind(rng: np.random.Generator, rz: Randomization) -> tuple[int, str]:
    """The first draws of a scene: its world seed and seabed kind (what a scene costs to build
    depends mostly on the kind: rough and rippled beds are terrain meshes)."""
    return int(rng.integers(0, 2**31 - 1)), str(rng.choice(rz.seabed_kinds))


def sample_scene(index: int, rng: np.random.Generator, rz: Randomization, seabed_depth_fn) -> SceneSpec:
    """Draw scene ``index``. ``seabed_depth_fn(seabed_cfg, world_seed)`` returns
    ``depth(n, e)`` of the seabed that will be built (rough/ripple beds are random fields)."""
    world_seed, kind = draw_world_seed_and_seabed_kind(rng, rz)
    range_max = _u(rng, rz.range_max_m)
    seabed = SeabedConfig(
        kind=kind, depth_m=_u(rng, rz.seabed_depth_m), slope_deg=_u(rng, rz.slope_deg) if kind == "slope" else 0.0,
        slope_azimuth_deg=_u(rng, (-180.0, 180.0)), roughness_m=_u(rng, rz.roughness_m),
        roughness_corr_m=_u(rng, rz.roughness_corr_m), ripple_amplitude_m=_u(rng, rz.ripple_amplitude_m),
        ripple_wavelength_m=_u(rng, rz.ripple_wavelength_m), ripple_azimuth_deg=_u(rng, (-180.0, 180.0)),
        extent_m=float(np.ceil(2.0 * range_max + 30.0)), mesh_resolution_m=0.5,
        reflectivity=_u(rng, rz.seabed_reflectivity))
    depth = seabed_depth_fn(seabed, world_seed)
    yaw = _u(rng, (-np.pi, np.pi))
    heading = np.array([np.cos(yaw), np.sin(yaw)])
    steps = [0.0]
    for _ in range(rz.frames_per_scene - 1):
        steps.append(steps[-1] + _u(rng, rz.step_m))
    altitude = _u(rng, rz.altitude_m)
    jit = np.deg2rad(rz.roll_pitch_jitter_deg)
    poses = []
    for s in steps:
        ne = heading * s
        z = float(depth(ne[0], ne[1])) - altitude
        poses.append(ScenePose((float(ne[0]), float(ne[1]), z),
                               (_u(rng, (-jit, jit)), _u(rng, (-jit, jit)), yaw + _u(rng, (-0.05, 0.05)))))
    range_min = _u(rng, rz.range_min_m)
    tilt = float(np.deg2rad(_u(rng, rz.tilt_deg)))
    # Nearest seabed range inside the vertical beam (flat-bed estimate); objects go beyond it.
    lower_edge = tilt + 0.5 * np.deg2rad(rz.vertical_beamwidth_deg)
    r_bed = altitude / np.sin(lower_edge) if lower_edge > 0 else 0.0
    r_lo = min(max(range_min + 1.0, np.sqrt(max(r_bed**2 - altitude**2, 0.0)) + 1.0), range_max - 3.0)
    # Objects spread over the area the frames look at: ahead of the first pose, within the fan.
    travel = steps[-1]
    objects: list[TargetConfig] = []
    n_t = int(rng.integers(rz.n_targets[0], rz.n_targets[1] + 1))
    n_d = int(rng.integers(rz.n_distractors[0], rz.n_distractors[1] + 1))
    for k in range(n_t + n_d):
        is_target = k < n_t
        r = _u(rng, (r_lo, range_max - 1.0)) + _u(rng, (0.0, travel))
        az = _u(rng, (-1.0, 1.0))
        pos = heading * r * np.cos(az) + np.array([-heading[1], heading[0]]) * r * np.sin(az)
        prefix = "t" if is_target else "d"
        objects.append(_object(rng, f"{prefix}{k}", pos, depth, rz, is_target))
        if is_target and rng.random() < rz.cluster_probability:
            for m in range(int(rng.integers(1, 3))):
                ang = _u(rng, (-np.pi, np.pi))
                off = _u(rng, rz.cluster_spacing_m) * np.array([np.cos(ang), np.sin(ang)])
                objects.append(_object(rng, f"{prefix}{k}c{m}", pos + off, depth, rz, bool(rng.random() < 0.7)))
    basin = BasinConfig()
    if rz.basin is not None and rng.random() < rz.basin.probability:
        basin = _sample_basin(rng, rz.basin, heading)
    return SceneSpec(index=index, world_seed=world_seed, seabed=seabed, targets=tuple(objects), basin=basin,
                     poses=tuple(poses), tilt_rad=tilt, range_min_m=range_min,
                     range_max_m=range_max, gain_db=_u(rng, rz.gain_db), noise_scale=_u(rng, rz.noise_scale),
                     speckle="k" if rng.random() < rz.k_speckle_probability else "rayleigh",
                     k_shape=_u(rng, rz.k_shape))


def _sample_basin(rng: np.random.Generator, rb: BasinRandomization, heading: NDArray) -> BasinConfig:
    """Rectangular basin around the first pose (at the origin) with the wall faced along the
    dominant axis of ``heading`` (unit NE vector) at slant range ``rb.wall_range_m`` ahead."""
    half = np.array([_u(rng, rb.half_size_m), _u(rng, rb.half_size_m)])
    k = int(np.argmax(np.abs(heading)))
    sign = float(np.sign(heading[k])) or 1.0
    d_axis = _u(rng, rb.wall_range_m) * abs(heading[k])
    half[k] = max(half[k], d_axis + 1.0)
    centre = np.zeros(2)
    centre[k] = sign * (d_axis - half[k])
    centre[1 - k] = _u(rng, (-0.5, 0.5)) * half[1 - k]
    return BasinConfig(shape="rectangular", center_ne_m=(float(centre[0]), float(centre[1])),
                       size_ne_m=(float(2 * half[0]), float(2 * half[1])), reflectivity=_u(rng, rb.reflectivity))
