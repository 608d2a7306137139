"""Generate the FeelHippo visual mesh and MJCF (sim/assets/feelhippo/).

The mesh is a low-poly stand-in assembled from trimesh primitives inside the paper's
0.60 x 0.64 x 0.50 m envelope: an upper pressure hull, two lower side floats, a top
buoyancy block, skids, and the four thruster ducts at the positions of params.yaml.
Usage: ``python scripts/make_feelhippo_mesh.py`` (rewrites feelhippo_visual.stl and
feelhippo.xml; both are committed).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from scenarios.config.vehicle import VehicleConfig
from sim.dynamics.hull import write_mjcf
from scenarios.vehicle_params import load_vehicle_params

ASSET_DIR = Path(__file__).resolve().parents[1] / "sim" / "assets" / "feelhippo"


def _cyl_x(radius: float, length: float, center, sections: int = 20) -> trimesh.Trimesh:
    c = trimesh.creation.cylinder(radius=radius, height=length, sections=sections)
    c.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))
    c.apply_translation(center)
    return c


def _cyl_axis(radius: float, length: float, center, axis, sections: int = 16) -> trimesh.Trimesh:
    c = trimesh.creation.cylinder(radius=radius, height=length, sections=sections)
    z = np.array([0.0, 0.0, 1.0])
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    if not np.allclose(a, z) and not np.allclose(a, -z):
        ang = np.arccos(np.clip(z @ a, -1, 1))
        c.apply_transform(trimesh.transformations.rotation_matrix(ang, np.cross(z, a)))
    c.apply_translation(center)
    return c


def _box(extents, center) -> trimesh.Trimesh:
    b = trimesh.creation.box(extents=extents)
    b.apply_translation(center)
    return b


def feelhippo_mesh() -> trimesh.Trimesh:
    """Visual mesh in the body frame (FRD, metres, origin at CO)."""
    params = load_vehicle_params(VehicleConfig(model="feelhippo"))
    parts = [
        _cyl_x(0.10, 0.50, [0.02, 0.0, -0.08]),           # main pressure hull (upper)
        _cyl_x(0.07, 0.56, [0.0, -0.20, 0.10]),           # port float
        _cyl_x(0.07, 0.56, [0.0, 0.20, 0.10]),            # starboard float
        _box([0.46, 0.50, 0.05], [0.0, 0.0, -0.215]),     # top buoyancy block
        _box([0.50, 0.03, 0.04], [0.0, -0.20, 0.23]),     # skids
        _box([0.50, 0.03, 0.04], [0.0, 0.20, 0.23]),
        _box([0.05, 0.46, 0.38], [0.20, 0.0, 0.0]),       # front frame
        _box([0.05, 0.46, 0.38], [-0.12, 0.0, 0.0]),      # rear frame
        _cyl_x(0.08, 0.10, [0.30 - 0.05, 0.0, 0.15], 16),  # sonar head
    ]
    for pos, d in zip(params.layout.pos_body_m, params.layout.dir_body):
        parts.append(_cyl_axis(0.05, 0.09, pos, d))        # thruster ducts
    mesh = trimesh.util.concatenate(parts)
    lo, hi = mesh.bounds
    env = params.envelope_m
    assert np.all(hi - lo <= env + 1e-9), f"mesh {hi - lo} exceeds envelope {env}"
    return mesh


def main() -> None:
    mesh = feelhippo_mesh()
    stl = ASSET_DIR / "feelhippo_visual.stl"
    mesh.export(stl)
    print(f"wrote {stl} ({len(mesh.faces)} faces, bounds {mesh.bounds.tolist()})")
    xml = write_mjcf(load_vehicle_params(VehicleConfig(model="feelhippo")), ASSET_DIR / "feelhippo.xml")
    print(f"wrote {xml}")


if __name__ == "__main__":
    main()
