"""Meshes of marine debris: the object kinds of the Marine Debris forward-looking sonar set
([MarineDebrisFLS] in ``docs/references.md``), built with trimesh ([trimesh]).

Every mesh follows :mod:`sim.scene.target_meshes`' convention: NED-aligned local frame, base
on z = 0, extending upwards (towards negative z), outward normals, each part a closed
surface. Its axis-aligned box in the default orientation is exactly the config's ``size_m``
(length along x, width along y, height along z): each solid is built at unit proportions and
scaled to it. Default orientation: lying on the bottom, long axis along x. A standing bottle
is a ``bottle`` pitched 90 deg (``rpy_deg: [0, 90, 0]``) with ``pos_ned`` raised by half its
length (its base end, at -x, then rests on the bottom).

Default sizes (:func:`debris_default_size_m`; estimates of common objects, and the real
set's boxes at about 5 mm per pixel):

| shape | length x width x height, m | built from |
|---|---|---|
| ``bottle`` | 0.25 x 0.08 x 0.08 | revolved profile: body, shoulder, neck, cap |
| ``can`` | 0.12 x 0.066 x 0.066 | revolved profile with rims |
| ``chain`` | 0.45 x 0.035 x 0.035 | 9 oval links, alternate links turned 90 deg |
| ``drink_carton`` | 0.2 x 0.095 x 0.07 | a brick and its gable top |
| ``hook`` | 0.15 x 0.08 x 0.012 | bent round bar (J) with an eye |
| ``propeller`` | 0.3 x 0.3 x 0.06 | hub and three pitched blades, lying flat |
| ``shampoo_bottle`` | 0.2 x 0.08 x 0.045 | revolved profile, flattened section |
| ``valve`` | 0.2 x 0.1 x 0.12 | body, two flanges, stem and hand-wheel |

The meshes are built on first use and cached; ``trimesh`` is imported then, not with the module.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

DEBRIS_SIZES_M: dict[str, tuple[float, float, float]] = {
    "bottle": (0.25, 0.08, 0.08), "can": (0.12, 0.066, 0.066), "chain": (0.45, 0.035, 0.035),
    "drink_carton": (0.2, 0.095, 0.07), "hook": (0.15, 0.08, 0.012), "propeller": (0.3, 0.3, 0.06),
    "shampoo_bottle": (0.2, 0.08, 0.045), "valve": (0.2, 0.1, 0.12)}
DEBRIS_SHAPES = tuple(DEBRIS_SIZES_M)


def debris_default_size_m(shape: str) -> tuple[float, float, float]:
    """The default ``(length, width, height)`` of a debris shape, m.

    Raises:
        KeyError: not a debris shape (:data:`DEBRIS_SHAPES`).
    """
    return DEBRIS_SIZES_M[shape]


def _revolved_along_x(profile_rz: list[tuple[float, float]], sections: int = 24):
    """A solid of revolution about x from a (radius, axial position) profile (axial 0..1)."""
    import trimesh

    m = trimesh.creation.revolve(np.asarray(profile_rz, dtype=float), sections=sections)
    m.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))  # z axis -> x
    return [m]


def _bottle():
    return _revolved_along_x([(0.0, 0.0), (0.92, 0.0), (1.0, 0.04), (1.0, 0.62), (0.9, 0.72), (0.45, 0.84),
                              (0.34, 0.88), (0.34, 0.93), (0.42, 0.93), (0.42, 1.0), (0.0, 1.0)])


def _shampoo_bottle():
    return _revolved_along_x([(0.0, 0.0), (0.95, 0.0), (1.0, 0.05), (1.0, 0.7), (0.8, 0.82), (0.45, 0.86),
                              (0.45, 1.0), (0.0, 1.0)])


def _can():
    return _revolved_along_x([(0.0, 0.02), (0.82, 0.0), (0.88, 0.03), (1.0, 0.09), (1.0, 0.91), (0.88, 0.97),
                              (0.82, 1.0), (0.0, 0.98)], sections=32)


def _chain(n_links: int = 9):
    import trimesh

    parts = []
    pitch = 1.0  # link centres one unit apart; each link 1.6 long, 0.8 wide (oval torus)
    for k in range(n_links):
        link = trimesh.creation.torus(major_radius=0.4, minor_radius=0.1, major_sections=24, minor_sections=8)
        link.apply_scale([1.5, 1.0, 1.0])  # oval along x (still closed)
        if k % 2:
            link.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
        link.apply_translation([k * pitch, 0.0, 0.0])
        parts.append(link)
    return parts


def _drink_carton():
    import trimesh

    brick = trimesh.creation.box(extents=[0.82, 1.0, 1.0])
    brick.apply_translation([-0.09, 0.0, 0.0])
    # gable top: a triangular prism along y on the +x end
    v = np.array([[0.32, -0.5, -0.5], [0.32, -0.5, 0.5], [0.5, -0.5, 0.0],
                  [0.32, 0.5, -0.5], [0.32, 0.5, 0.5], [0.5, 0.5, 0.0]])
    f = np.array([[0, 2, 1], [3, 4, 5], [0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [0, 3, 5], [0, 5, 2]])
    gable = trimesh.Trimesh(v, f, process=True)
    gable.fix_normals()
    return [brick, gable]


def _bar(points: np.ndarray, radius: float, sections: int = 10):
    """A bent round bar along a polyline: a cylinder per segment and a sphere at each joint."""
    import trimesh

    parts = []
    for a, b in zip(points[:-1], points[1:]):
        seg = trimesh.creation.cylinder(radius=radius, segment=np.array([a, b]), sections=sections)
        parts.append(seg)
    for p in points[1:-1]:
        s = trimesh.creation.icosphere(subdivisions=1, radius=radius)
        s.apply_translation(p)
        parts.append(s)
    return parts


def _hook():
    import trimesh

    shank = [np.array([x, 0.0, 0.0]) for x in np.linspace(-1.0, 0.4, 4)]
    ang = np.linspace(-np.pi / 2, np.pi / 2, 9)
    bend = [np.array([0.4 + 0.5 * np.cos(a), 0.5 + 0.5 * np.sin(a), 0.0]) for a in ang]
    tip = [np.array([0.1, 1.0, 0.0])]
    parts = _bar(np.array(shank + bend[1:] + tip), 0.08)
    eye = trimesh.creation.torus(major_radius=0.14, minor_radius=0.06, major_sections=16, minor_sections=8)
    eye.apply_translation([-1.2, 0.0, 0.0])
    return parts + [eye]


def _propeller():
    import trimesh

    hub = trimesh.creation.cylinder(radius=0.12, height=1.0, sections=20)
    parts = [hub]
    for k in range(3):
        blade = trimesh.creation.box(extents=[0.85, 0.32, 0.06])
        blade.apply_transform(trimesh.transformations.rotation_matrix(np.deg2rad(30.0), [1, 0, 0]))  # pitch
        blade.apply_translation([0.12 + 0.425, 0.0, 0.0])
        blade.apply_transform(trimesh.transformations.rotation_matrix(2 * np.pi * k / 3, [0, 0, 1]))
        parts.append(blade)
    return parts


def _valve():
    import trimesh

    rot_x = trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0])
    body = trimesh.creation.cylinder(radius=0.28, height=1.0, sections=20)
    body.apply_transform(rot_x)
    parts = [body]
    for x in (-0.45, 0.45):
        fl = trimesh.creation.cylinder(radius=0.5, height=0.1, sections=24)
        fl.apply_transform(rot_x)
        fl.apply_translation([x, 0.0, 0.0])
        parts.append(fl)
    stem = trimesh.creation.cylinder(radius=0.06, height=0.9, sections=12)
    stem.apply_translation([0.0, 0.0, 0.45])
    wheel = trimesh.creation.torus(major_radius=0.35, minor_radius=0.05, major_sections=24, minor_sections=8)
    wheel.apply_translation([0.0, 0.0, 0.9])
    return parts + [stem, wheel]


_BUILDERS = {"bottle": _bottle, "can": _can, "chain": _chain, "drink_carton": _drink_carton, "hook": _hook,
             "propeller": _propeller, "shampoo_bottle": _shampoo_bottle, "valve": _valve}


@lru_cache(maxsize=64)
def debris_mesh_arrays(shape: str, size_m: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (n, 3) float64 and faces (m, 3) int64 (outward, counter-clockwise seen from
    outside) of debris ``shape`` scaled to the box ``size_m`` (length, width, height, m), base
    on z = 0, extending to z = -height (read-only arrays;
    :func:`sim.scene.target_meshes.debris_mesh` wraps them).

    Raises:
        ValueError: not a debris shape, or a size that is not positive.
    """
    if shape not in _BUILDERS:
        raise ValueError(f"unknown debris shape {shape!r}; one of {', '.join(DEBRIS_SHAPES)}")
    size = np.asarray(size_m, dtype=float)
    if size.shape != (3,) or np.any(size <= 0):
        raise ValueError(f"debris size_m must be three positive lengths, got {size_m}")
    parts = _BUILDERS[shape]()
    verts, faces, off = [], [], 0
    for p in parts:
        verts.append(np.asarray(p.vertices, dtype=float))
        faces.append(np.asarray(p.faces, dtype=np.int64) + off)
        off += len(p.vertices)
    v = np.concatenate(verts)
    f = np.concatenate(faces)
    lo, hi = v.min(axis=0), v.max(axis=0)
    v = (v - lo) / (hi - lo) * size  # into [0, size] on each axis (z up)
    v[:, 0] -= 0.5 * size[0]
    v[:, 1] -= 0.5 * size[1]
    v[:, 2] = -v[:, 2]  # z up -> z down (NED): the mirror flips the winding back outward below
    f = f[:, ::-1].copy()
    v.setflags(write=False)
    f.setflags(write=False)
    return v, f
