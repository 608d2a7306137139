"""Build the MuJoCo scene from a scenario with MjSpec: seabed, basin walls, targets, hull.

The MuJoCo world frame is NED (z down) and MuJoCo gravity is off: weight and buoyancy
act through the hydrodynamic wrench (:mod:`sim.dynamics.vehicle`). Geom groups:

* ``ACOUSTIC_GROUP`` (0): what sonars and ray-cast sensors see (seabed, walls, targets);
* ``HULL_GROUP`` (1, :mod:`sim.dynamics.hull`): the vehicles' geoms (the AUV's and those of the
  extra vehicles of ``scenario.vehicles``, e.g. a surface buoy): no sonar sees them and
  they are no scene object;
* ``COLLISION_PROXY_GROUP`` (3): invisible collision stand-ins (a plane under a terrain
  mesh, since MuJoCo collides meshes through their convex hulls).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field, replace

import mujoco
import numpy as np
from numpy.typing import NDArray

from autonomy.frames import quat_from_rot, rot_from_euler
from scenarios.config.world import BasinConfig, TargetConfig, WorldConfig
from scenarios.schema import Scenario
from sim.rng import component_rng
from sim.scene.seabed import Seabed, make_seabed
from sim.sensors.raycast import BACKGROUND_ID
from sim.dynamics.hull import VEHICLE_BODY, build_hull_spec
from sim.scene.target_meshes import target_mesh
from sim.scene.movers import add_mover_bodies
from scenarios.vehicle_params import load_params_file, load_vehicle_params, params_path

ACOUSTIC_GROUP = 0
COLLISION_PROXY_GROUP = 3
HULL_PREFIX = "hull/"
NO_OBJECT_ID = -3  # geoms that belong to no scene object and are not background (hull)

_INTEGRATORS = {
    "euler": mujoco.mjtIntegrator.mjINT_EULER,
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
    "rk4": mujoco.mjtIntegrator.mjINT_RK4,
}


@dataclass(frozen=True)
class SceneObject:
    """A labelled object on the seabed.

    Attributes:
        id: object id, 0..n-1 in scenario order (the id rays report).
        centroid_ned: (3,) volume centroid in NED, m.
        base_ned: (3,) centre of the object's base (its configured position).
        bounding_radius_m: radius of a sphere about the centroid containing the object.
        height_m: height above its base.
    """

    id: int
    name: str
    class_name: str
    is_target: bool
    shape: str
    centroid_ned: NDArray[np.float64]
    base_ned: NDArray[np.float64]
    bounding_radius_m: float
    height_m: float
    reflectivity: float
    geom_id: int = -1


@dataclass
class World:
    """A compiled scene and the tables sensors need.

    Attributes:
        geom_object_id: (ngeom,) object id per geom: 0..n-1 for scene objects,
            ``BACKGROUND_ID`` (-1) for seabed/walls, ``NO_OBJECT_ID`` for the hull.
        geom_reflectivity: (ngeom,) acoustic reflectivity per geom in [0, 1].
    """

    spec: mujoco.MjSpec
    model: mujoco.MjModel
    data: mujoco.MjData
    seabed: Seabed
    objects: tuple[SceneObject, ...]
    geom_object_id: NDArray[np.int64]
    geom_reflectivity: NDArray[np.float64]
    vehicle_body_id: int
    site_ids: dict[str, int] = field(default_factory=dict)
    #: body id of each extra vehicle (``scenario.vehicles``), attached under ``<name>/``.
    extra_body_ids: dict[str, int] = field(default_factory=dict)

    def site_pos_body(self, name: str) -> NDArray[np.float64]:
        """Offset (FRD, m) of a hull site from the vehicle body origin."""
        return np.array(self.model.site_pos[self.site_ids[name]], dtype=float)

    @property
    def acoustic_geomgroup(self) -> NDArray[np.uint8]:
        """``geomgroup`` mask for ``mj_multiRay`` selecting only acoustic geoms."""
        mask = np.zeros(6, dtype=np.uint8)
        mask[ACOUSTIC_GROUP] = 1
        return mask


def _quat_wxyz(rpy_rad: tuple[float, float, float] | NDArray) -> list[float]:
    return quat_from_rot(rot_from_euler(*rpy_rad)).tolist()


def _quat_z_to(normal: NDArray) -> list[float]:
    """Quaternion rotating the local +z axis onto ``normal``."""
    z = np.array([0.0, 0.0, 1.0])
    n = normal / np.linalg.norm(normal)
    axis = np.cross(z, n)
    s = np.linalg.norm(axis)
    if s < 1e-12:
        return [1.0, 0.0, 0.0, 0.0] if n[2] > 0 else [0.0, 1.0, 0.0, 0.0]
    angle = np.arctan2(s, float(z @ n))
    axis /= s
    return [np.cos(angle / 2), *(np.sin(angle / 2) * axis)]


def _add_msh_asset(spec: mujoco.MjSpec, stem: str, vertices: NDArray, faces: NDArray) -> str:
    """Put a triangle mesh into ``spec``'s assets in MuJoCo's binary ``.msh`` layout and return
    its file name (``stem`` plus a digest of the content).

    The layout (int32 vertex, normal, texcoord and face counts; float32 vertices; int32 faces)
    holds the same float32 vertices and faces as ``uservert`` / ``userface``, so the compiled
    mesh is the same, but MuJoCo reads it in C: a 65k-vertex seabed takes 0.4 ms instead of the
    ~20 ms the Python binding spends converting the arrays. MuJoCo caches meshes read from
    files; :func:`build_world` clears that cache after compiling (a seabed is read once and
    would hold ~50 MB there).
    """
    v = np.ascontiguousarray(vertices, dtype=np.float32)
    f = np.ascontiguousarray(faces, dtype=np.int32)
    payload = np.array([len(v), 0, 0, len(f)], dtype=np.int32).tobytes() + v.tobytes() + f.tobytes()
    name = f"{stem}_{hashlib.blake2b(payload, digest_size=12).hexdigest()}.msh"
    spec.assets = {**spec.assets, name: payload}
    return name


def _add_seabed(spec: mujoco.MjSpec, seabed: Seabed) -> list[mujoco.MjsGeom]:
    cfg = seabed.cfg
    center = np.array([cfg.center_ne_m[0], cfg.center_ne_m[1], 0.0])
    center[2] = float(seabed.depth_at(center[0], center[1]))
    if not seabed.is_mesh:
        half = 0.5 * cfg.extent_m / np.cos(np.deg2rad(cfg.slope_deg))
        geom = spec.worldbody.add_geom(
            name="seabed", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[half, half, 1.0],
            pos=center.tolist(), quat=_quat_z_to(seabed.plane_normal_ned()), group=ACOUSTIC_GROUP,
            rgba=[0.55, 0.5, 0.4, 1.0],
        )
        return [geom]
    vertices, faces = seabed.terrain_arrays()
    spec.add_mesh(name="seabed_mesh", file=_add_msh_asset(spec, "seabed", vertices, faces))
    geom = spec.worldbody.add_geom(
        name="seabed", type=mujoco.mjtGeom.mjGEOM_MESH, meshname="seabed_mesh", group=ACOUSTIC_GROUP,
        contype=0, conaffinity=0, rgba=[0.55, 0.5, 0.4, 1.0],
    )
    half = 0.5 * cfg.extent_m
    proxy_depth = float(np.nanmax(seabed.depth_grid_m))
    spec.worldbody.add_geom(
        name="seabed_collision", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[half, half, 1.0],
        pos=[center[0], center[1], proxy_depth], quat=[0.0, 1.0, 0.0, 0.0], group=COLLISION_PROXY_GROUP,
        rgba=[0, 0, 0, 0],
    )
    return [geom]


def _add_basin(spec: mujoco.MjSpec, basin: BasinConfig, seabed: Seabed) -> list[mujoco.MjsGeom]:
    if basin.shape == "none":
        return []
    cn, ce = basin.center_ne_m
    t = basin.wall_thickness_m
    if basin.shape == "rectangular":
        ln, le = basin.size_ne_m
        corners_n = np.array([cn - ln / 2, cn + ln / 2])
        corners_e = np.array([ce - le / 2, ce + le / 2])
        bottom = float(np.max(seabed.depth_at(*np.meshgrid(corners_n, corners_e)))) + 0.5
        # (centre n, centre e, half n, half e)
        walls = [
            (cn + (ln + t) / 2, ce, t / 2, le / 2 + t),
            (cn - (ln + t) / 2, ce, t / 2, le / 2 + t),
            (cn, ce + (le + t) / 2, ln / 2 + t, t / 2),
            (cn, ce - (le + t) / 2, ln / 2 + t, t / 2),
        ]
        geoms = []
        for i, (n, e, hn, he) in enumerate(walls):
            geoms.append(spec.worldbody.add_geom(
                name=f"basin_wall_{i}", type=mujoco.mjtGeom.mjGEOM_BOX, size=[hn, he, (bottom + 0.5) / 2],
                pos=[n, e, (bottom - 0.5) / 2], group=ACOUSTIC_GROUP, rgba=[0.6, 0.6, 0.65, 0.3],
            ))
        return geoms
    n_seg = 64
    r = basin.radius_m + t / 2
    ang = np.linspace(0.0, 2 * np.pi, n_seg, endpoint=False)
    bottom = float(np.max(seabed.depth_at(cn + r * np.cos(ang), ce + r * np.sin(ang)))) + 0.5
    seg_half = r * np.tan(np.pi / n_seg) * 1.02
    geoms = []
    for i, a in enumerate(ang):
        geoms.append(spec.worldbody.add_geom(
            name=f"basin_wall_{i}", type=mujoco.mjtGeom.mjGEOM_BOX, size=[t / 2, seg_half, (bottom + 0.5) / 2],
            pos=[cn + r * np.cos(a), ce + r * np.sin(a), (bottom - 0.5) / 2],
            quat=_quat_wxyz((0.0, 0.0, a)), group=ACOUSTIC_GROUP, rgba=[0.6, 0.6, 0.65, 0.3],
        ))
    return geoms


def _add_target(spec: mujoco.MjSpec, idx: int, cfg: TargetConfig) -> tuple[mujoco.MjsGeom, SceneObject]:
    mesh = target_mesh(cfg)
    mesh_name = f"target_mesh_{idx}"
    spec.add_mesh(name=mesh_name, uservert=mesh.vertices.astype(np.float32).ravel(),
                  userface=mesh.faces.astype(np.int32).ravel())
    R = rot_from_euler(*np.deg2rad(cfg.rpy_deg))
    base = np.asarray(cfg.pos_ned, dtype=float)
    geom = spec.worldbody.add_geom(
        name=f"target:{cfg.name}", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh_name,
        pos=base.tolist(), quat=_quat_wxyz(np.deg2rad(cfg.rpy_deg)), group=ACOUSTIC_GROUP,
        rgba=[0.9, 0.6, 0.1, 1.0] if cfg.is_target else [0.5, 0.5, 0.5, 1.0],
    )
    centroid_local = np.asarray(mesh.center_mass, dtype=float)
    radius = float(np.max(np.linalg.norm(mesh.vertices - centroid_local, axis=1)))
    obj = SceneObject(
        id=idx, name=cfg.name, class_name=cfg.class_name, is_target=cfg.is_target, shape=cfg.shape,
        centroid_ned=base + R @ centroid_local, base_ned=base, bounding_radius_m=radius,
        height_m=float(-mesh.bounds[0, 2]), reflectivity=cfg.reflectivity,
    )
    return geom, obj


def build_world(scenario: Scenario, *, with_vehicle: bool = True) -> World:
    """Compile the scenario's scene. ``with_vehicle=False`` leaves the hull out (sensor tests)."""
    spec = mujoco.MjSpec()
    spec.modelname = scenario.name
    spec.option.gravity = [0.0, 0.0, 0.0]
    spec.option.timestep = 1.0 / scenario.physics.rate_hz
    spec.option.integrator = _INTEGRATORS[scenario.physics.integrator]
    spec.stat.extent = max(scenario.world.seabed.extent_m, 10.0)

    wcfg: WorldConfig = scenario.world
    seabed = make_seabed(wcfg.seabed, component_rng(scenario.seed, "seabed"))
    background = _add_seabed(spec, seabed) + _add_basin(spec, wcfg.basin, seabed)
    reflect_of = {id(g): wcfg.seabed.reflectivity for g in background[:1]}
    reflect_of.update({id(g): wcfg.basin.reflectivity for g in background[1:]})

    target_geoms = []
    objects = []
    # Without a vehicle nothing can touch a target (world geoms never collide with each other):
    # collisions off, so MuJoCo builds no convex hull of its mesh (about 2 ms a scene of dataset
    # objects; what rays see is unchanged: same vertices, faces, poses and bounding volumes).
    inert = not with_vehicle and not scenario.vehicles
    for i, tcfg in enumerate(wcfg.targets):
        geom, obj = _add_target(spec, i, tcfg)
        if inert:
            geom.contype = geom.conaffinity = 0
        target_geoms.append(geom)
        objects.append(obj)

    mover_geoms = add_mover_bodies(spec, wcfg.movers, ACOUSTIC_GROUP)
    for j, mg in enumerate(mover_geoms):
        target_geoms.append(mg.geom)
        objects.append(SceneObject(
            id=len(wcfg.targets) + j, name=mg.name, class_name=mg.class_name, is_target=mg.is_target,
            shape=mg.shape, centroid_ned=np.zeros(3), base_ned=np.zeros(3), bounding_radius_m=mg.radius_m,
            height_m=mg.height_m, reflectivity=mg.reflectivity))

    if with_vehicle:
        hull = build_hull_spec(load_vehicle_params(scenario.vehicle))
        frame = spec.worldbody.add_frame()
        frame.attach_body(hull.body(VEHICLE_BODY), HULL_PREFIX, "")

    for name, vcfg in scenario.vehicles.items():  # after the AUV: its ids stay those of a single-vehicle scene
        extra = build_hull_spec(load_params_file(params_path(vcfg.preset)))
        spec.worldbody.add_frame().attach_body(extra.body(VEHICLE_BODY), f"{name}/", "")

    model = spec.compile()
    if spec.assets:  # meshes read from assets (the seabed) stay in MuJoCo's cache: free them
        mujoco.mj_clearCache(mujoco.mj_getCache())
    data = mujoco.MjData(model)

    geom_object_id = np.full(model.ngeom, NO_OBJECT_ID, dtype=np.int64)
    geom_reflectivity = np.zeros(model.ngeom)
    for g in background:
        gid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, g.name)
        geom_object_id[gid] = BACKGROUND_ID
        geom_reflectivity[gid] = reflect_of[id(g)]
    final_objects = []
    mujoco.mj_kinematics(model, data)  # mover geoms at their initial poses
    for g, obj in zip(target_geoms, objects):
        gid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, g.name)
        geom_object_id[gid] = obj.id
        geom_reflectivity[gid] = obj.reflectivity
        if model.body_mocapid[model.geom_bodyid[gid]] >= 0:  # a mover: centroid and base at its geom centre
            obj = replace(obj, centroid_ned=data.geom_xpos[gid].copy(), base_ned=data.geom_xpos[gid].copy())
        final_objects.append(replace(obj, geom_id=gid))

    vehicle_body_id = -1
    site_ids: dict[str, int] = {}
    if with_vehicle:
        vehicle_body_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, HULL_PREFIX + VEHICLE_BODY)
        for sid in range(model.nsite):
            name = model.site(sid).name
            if name.startswith(HULL_PREFIX):
                site_ids[name[len(HULL_PREFIX):]] = sid
    extra_body_ids = {name: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"{name}/{VEHICLE_BODY}")
                      for name in scenario.vehicles}
    mujoco.mj_forward(model, data)
    return World(spec, model, data, seabed, tuple(final_objects), geom_object_id, geom_reflectivity,
                 vehicle_body_id, site_ids, extra_body_ids)
