"""Build a vehicle hull as a ``mujoco.MjSpec`` from its :class:`VehicleParams`.

The spec's worldbody holds one body ``"vehicle"`` (origin at the centre of origin CO, FRD
axes) with a free joint (a ``surface_3dof`` preset: north/east slides and a yaw hinge at
its waterline depth), an explicit inertial (mass ``m``, CoM at ``r_bg``, inertia
``I_g``: the *rigid body only*; added mass, damping, weight and buoyancy act through
:mod:`sim.dynamics.vehicle`), a collision geom of the hull envelope, an optional visual mesh that
never collides, and sites for its sensor mounts (``fls``, ``dvl``, ``imu``, ``altimeter``,
``depth``, ``gps``, those it has) and
``thruster_<name>`` (site x axis along the thrust direction). All hull geoms are in
:data:`HULL_GROUP` so ray-cast sensors can leave them out. The scene builder attaches the
body with ``MjSpec`` attach.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from autonomy.frames import quat_from_euler, quat_from_rot
from scenarios.vehicle_params import SENSOR_NAMES, VehicleParams

VEHICLE_BODY = "vehicle"
HULL_GROUP = 1  # geom group of every hull geom (sim.scene.world's groups are documented there)
VISUAL_MESH = "hull_visual"

_SHAPES = {
    "box": (mujoco.mjtGeom.mjGEOM_BOX, lambda s: 0.5 * s),
    "ellipsoid": (mujoco.mjtGeom.mjGEOM_ELLIPSOID, lambda s: 0.5 * s),
    "cylinder_x": (mujoco.mjtGeom.mjGEOM_CYLINDER, lambda s: np.array([0.5 * s[1], 0.5 * s[0], 0.0])),
}


def _thruster_quat(direction: np.ndarray) -> list[float]:
    """Quaternion of a frame whose x axis is ``direction``."""
    x = direction / np.linalg.norm(direction)
    helper = np.array([0.0, 0.0, 1.0]) if abs(x[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    y = np.cross(helper, x)
    y /= np.linalg.norm(y)
    z = np.cross(x, y)
    return quat_from_rot(np.column_stack([x, y, z])).tolist()


def build_hull_spec(params: VehicleParams, *, mesh_from_file: bool = False) -> mujoco.MjSpec:
    """MjSpec holding the vehicle body (see module docstring).

    ``mesh_from_file`` references the visual mesh by file name (for writing a standalone
    MJCF next to it); by default its vertices are embedded, so the spec attaches anywhere.
    """
    spec = mujoco.MjSpec()
    spec.modelname = params.name
    spec.option.gravity = [0.0, 0.0, 0.0]
    body = spec.worldbody.add_body(name=VEHICLE_BODY)
    if params.motion == "surface_3dof":
        # North and east slides and a yaw hinge (NED z down: +angle turns x towards y);
        # the body origin rides at the waterline depth (Fossen's horizontal-plane model).
        body.pos = [0.0, 0.0, params.waterline_depth_m]
        body.add_joint(name="vehicle_north", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1.0, 0.0, 0.0])
        body.add_joint(name="vehicle_east", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0.0, 1.0, 0.0])
        body.add_joint(name="vehicle_yaw", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0.0, 0.0, 1.0])
    else:
        body.add_freejoint(name="vehicle_free")
    body.explicitinertial = True
    body.mass = params.mass_kg
    body.ipos = params.r_bg_m.tolist()
    I = params.inertia_cg_kgm2
    body.fullinertia = [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]

    hull = params.hull
    gtype, half = _SHAPES[hull.shape]
    quat = [1.0, 0.0, 0.0, 0.0]
    if hull.shape == "cylinder_x":  # MuJoCo cylinders lie along their local z
        quat = [np.sqrt(0.5), 0.0, np.sqrt(0.5), 0.0]
    body.add_geom(name="hull_collision", type=gtype, size=half(hull.size_m).tolist(),
                  pos=hull.center_body_m.tolist(), quat=quat, group=HULL_GROUP,
                  rgba=[0.9, 0.75, 0.1, 0.25 if hull.visual_mesh_path else 1.0])

    if hull.visual_mesh_path is not None:
        path = Path(hull.visual_mesh_path)
        if not path.is_file():
            raise FileNotFoundError(f"{params.name}: hull visual mesh not found: {path}")
        mesh = spec.add_mesh(name=VISUAL_MESH)
        mesh.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL
        if mesh_from_file:
            mesh.file = path.name
        else:
            import trimesh

            tm = trimesh.load_mesh(path)
            mesh.uservert = np.asarray(tm.vertices, dtype=np.float32).ravel().tolist()
            mesh.userface = np.asarray(tm.faces, dtype=np.int32).ravel().tolist()
        body.add_geom(name="hull_visual", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=VISUAL_MESH,
                      contype=0, conaffinity=0, group=HULL_GROUP, rgba=[0.95, 0.8, 0.1, 1.0])

    for name in (n for n in SENSOR_NAMES if n in params.sensors):
        mount = params.sensors[name]
        body.add_site(name=name, pos=mount.pos_body_m.tolist(),
                      quat=quat_from_euler(*mount.rpy_rad).tolist(), size=[0.02, 0.02, 0.02],
                      group=HULL_GROUP)
    lay = params.layout
    for name, pos, d in zip(lay.names, lay.pos_body_m, lay.dir_body):
        body.add_site(name=f"thruster_{name}", pos=pos.tolist(), quat=_thruster_quat(d),
                      size=[0.03, 0.03, 0.03], group=HULL_GROUP)
    return spec


def write_mjcf(params: VehicleParams, path: str | Path) -> Path:
    """Write the hull as a standalone MJCF (mesh referenced by file, same folder)."""
    path = Path(path)
    spec = build_hull_spec(params, mesh_from_file=True)
    spec.meshdir = str(path.parent)  # resolve the mesh while compiling ...
    xml = spec.to_xml()
    # ... but write the MJCF relocatable: the mesh is found next to the file.
    xml = xml.replace(f' meshdir="{path.parent}"', "")
    path.write_text(xml)
    return path


def build_standalone_spec(params: VehicleParams, *, timestep_s: float = 0.005,
                          integrator: str = "implicitfast", seabed_depth_m: float = 50.0,
                          prefix: str = "hull/") -> mujoco.MjSpec:
    """Minimal NED scene: a flat seabed plane at ``seabed_depth_m`` plus the hull attached
    under ``prefix`` exactly as the scene builder does (gravity off). For tests and tools
    that need the vehicle without a scenario world."""
    integrators = {"euler": mujoco.mjtIntegrator.mjINT_EULER,
                   "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
                   "rk4": mujoco.mjtIntegrator.mjINT_RK4}
    if integrator not in integrators:
        raise ValueError(f"integrator must be one of {sorted(integrators)}, got {integrator!r}")
    spec = mujoco.MjSpec()
    spec.modelname = f"{params.name}_standalone"
    spec.option.gravity = [0.0, 0.0, 0.0]
    spec.option.timestep = timestep_s
    spec.option.integrator = integrators[integrator]
    # A plane's normal is its local +z; flip it to point up (-z in NED).
    spec.worldbody.add_geom(name="seabed", type=mujoco.mjtGeom.mjGEOM_PLANE,
                            size=[100.0, 100.0, 0.1], pos=[0.0, 0.0, seabed_depth_m],
                            quat=[0.0, 1.0, 0.0, 0.0])
    spec.worldbody.add_frame().attach_body(build_hull_spec(params).body(VEHICLE_BODY), prefix, "")
    return spec
