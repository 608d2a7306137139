"""Vehicle parameter presets: rigid body, hydrostatics, hydrodynamics, thrusters, sensor mounts.

Each preset lives in ``sim/assets/<model>/params.yaml`` and is validated on load (unknown
keys, wrong shapes and out-of-range values raise :class:`VehicleParamsError` naming the file
and the key). Conventions (Fossen): body frame FRD with its origin at the centre of
origin CO (the MuJoCo body frame); ``r_bg_m`` / ``r_bb_m`` are the centres of gravity and
buoyancy from CO; added mass ``M_A`` and damping matrices are *positive* (``M_A = -[X_udot,
...]``), so the damping force is ``-(D_l + D_q |nu_r|) nu_r``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path
from typing import Annotated, Mapping

import numpy as np
import yaml
from numpy.typing import NDArray
from pydantic import Field, ValidationError

from autonomy.control.allocation import ThrusterLayout
from autonomy.frames import skew
from scenarios.config.base import NonNegFloat, PositiveFloat, StrictModel, Vec3
from scenarios.config.vehicle import VehicleConfig

FloatArray = NDArray[np.float64]
ASSETS_DIR = Path(str(resources.files("sim") / "assets"))  # the presets ship with the simulator package
SENSOR_NAMES = ("fls", "dvl", "imu", "altimeter", "depth", "gps")
#: Sensor mounts a preset must have, by its motion model (a surface vessel carries no sonar,
#: DVL or depth cell: GNSS and a compass/AHRS only).
REQUIRED_SENSORS = {"free_6dof": SENSOR_NAMES, "surface_3dof": ("imu", "gps")}
#: Motion models: ``free_6dof`` (a free body, Fossen's 6-DOF model, :mod:`sim.dynamics.vehicle`) or
#: ``surface_3dof`` (a surface vessel held at its waterline, level, moving in surge, sway
#: and yaw only: Fossen's horizontal-plane model, :mod:`sim.dynamics.surface_vessel`).
MOTION_MODELS = tuple(REQUIRED_SENSORS)
GRAVITY_MPS2 = 9.81


class VehicleParamsError(ValueError):
    """A vehicle parameter file is missing or invalid; the message names file and key."""


# ---------------------------------------------------------------------------- file schema
Vec6 = tuple[float, float, float, float, float, float]
Mat6 = tuple[Vec6, Vec6, Vec6, Vec6, Vec6, Vec6]


class _ThrusterFile(StrictModel):
    name: str = Field(min_length=1, pattern=r"^[A-Za-z0-9_]+$")
    pos_body_m: Vec3
    dir_body: Vec3
    max_fwd_n: PositiveFloat
    max_rev_n: PositiveFloat
    time_constant_s: NonNegFloat = 0.15
    dead_zone: Annotated[float, Field(ge=0.0, lt=0.5)] = 0.05
    curve_exponent: Annotated[float, Field(gt=0.0, le=4.0)] = 1.5


class _MountFile(StrictModel):
    pos_body_m: Vec3
    rpy_deg: Vec3 = (0.0, 0.0, 0.0)


class _HullFile(StrictModel):
    shape: str = Field(pattern=r"^(box|ellipsoid|cylinder_x)$")
    size_m: Vec3  # full extents along x, y, z (cylinder_x: length, diameter, diameter)
    center_body_m: Vec3 = (0.0, 0.0, 0.0)
    visual_mesh: str | None = None  # file name next to params.yaml


class _ParamsFile(StrictModel):
    name: str
    description: str = ""
    motion: str = Field("free_6dof", pattern=r"^(free_6dof|surface_3dof)$")
    waterline_depth_m: float = Field(0.0, ge=-5.0, le=5.0)  # surface_3dof: NED z of CO when afloat
    mass_kg: PositiveFloat
    inertia_cg_kgm2: Vec3 | tuple[Vec3, Vec3, Vec3]
    r_bg_m: Vec3
    r_bb_m: Vec3
    buoyancy_fraction: Annotated[float, Field(ge=0.5, le=1.5)]
    rho_kgpm3: Annotated[float, Field(ge=900.0, le=1100.0)] = 1025.0
    added_mass: Vec6 | Mat6
    damping_linear: Vec6 | Mat6
    damping_quadratic: Vec6 | Mat6
    damping_linear_decay_spm: Vec6 = (0.0,) * 6
    munk_moments: bool = True
    envelope_m: Vec3
    hull: _HullFile
    thrusters: tuple[_ThrusterFile, ...] = Field(min_length=1)
    sensors: dict[str, _MountFile]


# ---------------------------------------------------------------------------- runtime types
@dataclass(frozen=True, eq=False)
class SensorMount:
    """Fixed sensor pose on the hull: position (FRD, m, from CO) and roll/pitch/yaw (rad)."""

    pos_body_m: FloatArray
    rpy_rad: FloatArray


@dataclass(frozen=True, eq=False)
class HullShape:
    """Collision envelope of the hull (and optional visual mesh file path)."""

    shape: str  # "box" | "ellipsoid" | "cylinder_x"
    size_m: FloatArray  # (3,) full extents
    center_body_m: FloatArray  # (3,)
    visual_mesh_path: Path | None


@dataclass(frozen=True, eq=False)
class VehicleParams:
    """Everything the physics needs about one vehicle (SI units, FRD body frame at CO).

    Attributes:
        name: preset name.
        mass_kg: rigid-body (dry) mass m.
        inertia_cg_kgm2: (3, 3) inertia tensor about the CG, body axes.
        r_bg_m, r_bb_m: (3,) centres of gravity and buoyancy from CO.
        buoyancy_n, weight_n: B = rho g V and W = m g, N.
        rho_kgpm3, gravity_mps2: water density and gravity.
        added_mass: (6, 6) M_A (positive definite).
        damping_linear: (6, 6) D_l; damping_quadratic: (6, 6) D_q, with
            D(nu_r) nu_r = D_l' nu_r + D_q (|nu_r| * nu_r).
        damping_linear_decay_spm: (6,) k_i, row i of D_l scaled by exp(-k_i |v_r|)
            (Fossen's low-speed linear damping that fades at speed; 0 = constant).
        munk_moments: keep the Munk-moment entries of C_A(nu_r) (True, the full model);
            False zeroes the pitch/yaw Munk couplings as Fossen's library does for bare
            hulls whose stabilising fin lift is not modelled.
        thruster_time_constant_s: (n,) first-order rotor lag.
        layout: thruster geometry and command curves.
        envelope_m: (3,) overall length, width, height.
        hull: collision shape and visual mesh.
        sensors: name -> mount (:data:`REQUIRED_SENSORS` of its motion model).
        motion: ``free_6dof`` or ``surface_3dof`` (see :data:`MOTION_MODELS`).
        waterline_depth_m: surface_3dof only: NED z of CO while afloat (level, at rest), m.
    """

    name: str
    mass_kg: float
    inertia_cg_kgm2: FloatArray
    r_bg_m: FloatArray
    r_bb_m: FloatArray
    weight_n: float
    buoyancy_n: float
    rho_kgpm3: float
    gravity_mps2: float
    added_mass: FloatArray
    damping_linear: FloatArray
    damping_quadratic: FloatArray
    damping_linear_decay_spm: FloatArray
    thruster_time_constant_s: FloatArray
    layout: ThrusterLayout
    envelope_m: FloatArray
    hull: HullShape
    sensors: Mapping[str, SensorMount] = field(default_factory=dict)
    description: str = ""
    munk_moments: bool = True
    motion: str = "free_6dof"
    waterline_depth_m: float = 0.0

    @property
    def volume_m3(self) -> float:
        return self.buoyancy_n / (self.rho_kgpm3 * self.gravity_mps2)

    @property
    def inertia_co_kgm2(self) -> FloatArray:
        """(3, 3) inertia about CO: I_o = I_g - m S(r_g)^2 (parallel axes)."""
        S = skew(self.r_bg_m)
        return self.inertia_cg_kgm2 - self.mass_kg * S @ S

    @property
    def rigid_body_mass(self) -> FloatArray:
        """(6, 6) M_RB about CO (Fossen eq. 3.44)."""
        S = skew(self.r_bg_m)
        m = self.mass_kg
        return np.block([[m * np.eye(3), -m * S], [m * S, self.inertia_co_kgm2]])

    @property
    def mass_matrix(self) -> FloatArray:
        """(6, 6) M = M_RB + M_A."""
        return self.rigid_body_mass + self.added_mass

    @property
    def thruster_names(self) -> tuple[str, ...]:
        return self.layout.names

    @property
    def n_thrusters(self) -> int:
        return self.layout.n

    @property
    def thruster_matrix(self) -> FloatArray:
        """(6, n) thruster configuration matrix B: ``tau_body = B @ thrust_n``."""
        return self.layout.config_matrix()

    @property
    def thruster_limits_n(self) -> FloatArray:
        """(n, 2) thrust limits ``[-max_rev, max_fwd]`` in N."""
        return np.column_stack([-self.layout.max_rev_n, self.layout.max_fwd_n])


def _mat6(value, key: str, path: Path) -> FloatArray:
    arr = np.asarray(value, dtype=float)
    if arr.shape == (6,):
        arr = np.diag(arr)
    if arr.shape != (6, 6) or not np.all(np.isfinite(arr)):
        raise VehicleParamsError(f"{path}: '{key}' must be 6 numbers (diagonal) or a 6x6 matrix")
    return arr


def _ro(arr: FloatArray) -> FloatArray:
    arr = np.array(arr, dtype=float)
    arr.setflags(write=False)
    return arr


def params_path(model: str) -> Path:
    """Path of the parameter file of preset ``model``."""
    return ASSETS_DIR / model / "params.yaml"


def load_params_file(path: str | Path) -> VehicleParams:
    """Read and validate one ``params.yaml``."""
    path = Path(path)
    if not path.is_file():
        raise VehicleParamsError(f"vehicle parameter file not found: {path}")
    try:
        raw = yaml.safe_load(path.read_text()) or {}
    except yaml.YAMLError as exc:
        raise VehicleParamsError(f"{path}: not valid YAML: {exc}") from exc
    try:
        f = _ParamsFile.model_validate(raw)
    except ValidationError as exc:
        lines = [f"{path}: invalid vehicle parameters:"]
        for err in exc.errors():
            loc = ".".join(str(p) for p in err["loc"])
            lines.append(f"  {loc}: {err['msg']}")
        raise VehicleParamsError("\n".join(lines)) from None

    inertia = np.asarray(f.inertia_cg_kgm2, dtype=float)
    if inertia.shape == (3,):
        inertia = np.diag(inertia)
    if not np.allclose(inertia, inertia.T) or np.any(np.linalg.eigvalsh(inertia) <= 0):
        raise VehicleParamsError(f"{path}: 'inertia_cg_kgm2' must be symmetric positive definite")
    M_A = _mat6(f.added_mass, "added_mass", path)
    if not np.allclose(M_A, M_A.T, atol=1e-9) or np.any(np.linalg.eigvalsh(M_A) < 0):
        raise VehicleParamsError(f"{path}: 'added_mass' must be symmetric positive semi-definite")
    required = REQUIRED_SENSORS[f.motion]
    missing = [s for s in required if s not in f.sensors]
    if missing:
        raise VehicleParamsError(f"{path}: 'sensors' lacks {missing}; required: {list(required)}")
    names = [t.name for t in f.thrusters]
    if len(set(names)) != len(names):
        raise VehicleParamsError(f"{path}: 'thrusters' names must be unique, got {names}")

    layout = ThrusterLayout(
        names=tuple(names),
        pos_body_m=np.array([t.pos_body_m for t in f.thrusters]),
        dir_body=np.array([t.dir_body for t in f.thrusters]),
        max_fwd_n=np.array([t.max_fwd_n for t in f.thrusters]),
        max_rev_n=np.array([t.max_rev_n for t in f.thrusters]),
        dead_zone=np.array([t.dead_zone for t in f.thrusters]),
        curve_exponent=np.array([t.curve_exponent for t in f.thrusters]),
    )
    mesh = path.parent / f.hull.visual_mesh if f.hull.visual_mesh else None
    weight = f.mass_kg * GRAVITY_MPS2
    return VehicleParams(
        name=f.name,
        description=f.description,
        mass_kg=float(f.mass_kg),
        inertia_cg_kgm2=_ro(inertia),
        r_bg_m=_ro(f.r_bg_m),
        r_bb_m=_ro(f.r_bb_m),
        weight_n=weight,
        buoyancy_n=weight * f.buoyancy_fraction,
        rho_kgpm3=float(f.rho_kgpm3),
        gravity_mps2=GRAVITY_MPS2,
        added_mass=_ro(M_A),
        damping_linear=_ro(_mat6(f.damping_linear, "damping_linear", path)),
        damping_quadratic=_ro(_mat6(f.damping_quadratic, "damping_quadratic", path)),
        damping_linear_decay_spm=_ro(f.damping_linear_decay_spm),
        munk_moments=f.munk_moments,
        motion=f.motion,
        waterline_depth_m=float(f.waterline_depth_m),
        thruster_time_constant_s=_ro([t.time_constant_s for t in f.thrusters]),
        layout=layout,
        envelope_m=_ro(f.envelope_m),
        hull=HullShape(f.hull.shape, _ro(f.hull.size_m), _ro(f.hull.center_body_m), mesh),
        sensors={k: SensorMount(_ro(v.pos_body_m), _ro(np.deg2rad(v.rpy_deg)))
                 for k, v in f.sensors.items()},
    )


def with_overrides(params: VehicleParams, cfg: VehicleConfig) -> VehicleParams:
    """Apply the scenario's overrides (mass, buoyancy fraction, thruster options)."""
    out = params
    if cfg.mass_kg is not None:
        scale = cfg.mass_kg / params.mass_kg
        frac = params.buoyancy_n / params.weight_n
        weight = cfg.mass_kg * params.gravity_mps2
        out = replace(out, mass_kg=float(cfg.mass_kg), weight_n=weight, buoyancy_n=weight * frac,
                      inertia_cg_kgm2=_ro(params.inertia_cg_kgm2 * scale))
    if cfg.buoyancy_fraction is not None:
        out = replace(out, buoyancy_n=out.weight_n * cfg.buoyancy_fraction)
    t = cfg.thrusters
    if t.time_constant_s is not None:
        out = replace(out, thruster_time_constant_s=_ro(np.full(out.layout.n, t.time_constant_s)))
    if t.dead_zone is not None or t.thrust_scale != 1.0:
        lay = out.layout
        out = replace(out, layout=ThrusterLayout(
            names=lay.names, pos_body_m=lay.pos_body_m, dir_body=lay.dir_body,
            max_fwd_n=lay.max_fwd_n * t.thrust_scale, max_rev_n=lay.max_rev_n * t.thrust_scale,
            dead_zone=lay.dead_zone if t.dead_zone is None else np.full(lay.n, t.dead_zone),
            curve_exponent=lay.curve_exponent))
    return out


def load_vehicle_params(cfg: VehicleConfig) -> VehicleParams:
    """Parameters of the scenario's vehicle: the ``cfg.model`` preset plus overrides."""
    return with_overrides(load_params_file(params_path(cfg.model)), cfg)
