"""Meshes of marine debris: the object kinds of the Marine Debris forward-looking sonar set
([MarineDebrisFLS] in ``docs/references.md``: an ARIS 3000 in the Heriot-Watt water tank),
built with trimesh ([trimesh]).

Every mesh follows :mod:`sim.scene.target_meshes`' convention: NED-aligned local frame, base
centre at the origin, base on z = 0, extending upwards (towards negative z), outward normals,
each part a closed (watertight) surface; the parts of one object are concatenated, not fused
(they overlap; no boolean union). Its axis-aligned box in the default orientation is exactly
the config's ``size_m`` (length along local x, width along y, height along z): each solid is
built once at its real proportions (the default size below) and scaled per axis to the box.
Default orientation: lying on the bottom, long axis along x.

Default sizes (:func:`debris_default_size_m`), estimates of common real objects (not measured
on the real set), which scene generators scale; ``TargetConfig.size_m``'s own default, (1.0,
0.5, 0.5), is the box's and is left as it is:

=================== ========================= ==================================================
shape               length x width x height m built from
=================== ========================= ==================================================
``bottle``          0.25 x 0.08 x 0.08        revolved profile (1 l PET drink bottle, lying):
                                              base with push-up, body, shoulder, neck with its
                                              support ring, screw cap
``can``             0.12 x 0.066 x 0.066      revolved profile (330-355 ml drink can, lying):
                                              domed bottom with its standing ring, body, necked
                                              top with the seam rim and the recessed lid
``chain``           0.45 x 0.052 x 0.052      9 oval links of 15.5 mm round wire (link 5 d long,
                                              3.35 d wide, pitch 3 d), interlinked, lying along
                                              x: alternate links flat and on edge (turned 90 deg
                                              about the chain), so its height is a link's width
``drink_carton``    0.2 x 0.095 x 0.07        1 l brick carton lying on its broad face: brick,
                                              top seal fin and screw cap on its top end (+x)
``hook``            0.15 x 0.08 x 0.012       12 mm round bar bent into a J (shank, 26 mm bend,
                                              tapered point) with an eye ring on the shank end,
                                              lying flat
``propeller``       0.24 x 0.266 x 0.06       0.30 m diameter, three blades of 0.18 m pitch
                                              (twisted: pitch angle atan(P / 2 pi r)) on a 60 mm
                                              hub, lying flat on the hub; the box of three blades
                                              is not square (one tip on +x)
``shampoo_bottle``  0.2 x 0.08 x 0.045        revolved profile flattened to an elliptical
                                              section, lying on its broad face; flip-top cap
``valve``           0.2 x 0.1 x 0.12          gate valve standing on its two 100 mm flanges:
                                              body along x, bonnet, stem, hand-wheel (ring, hub,
                                              three spokes) on top
=================== ========================= ==================================================

The chain's height follows from its links: one on edge stands a link's width (about 3.35 wire
diameters) high; a box flatter than that squashes the links on edge.

**A standing bottle** is a ``bottle`` (or ``shampoo_bottle``, ``can``) pitched +90 deg:
``rpy_deg: [0, 90, yaw]`` turns local +x (base towards cap) upwards, so the base end, at
local -x, is down. Raise ``pos_ned`` by half the length: on a flat bottom at depth ``d``,
``pos_ned[2] = d - length / 2`` puts the flat base on it and the cap top at ``d - length``
(the bottle's axis is then half its diameter behind ``pos_ned``, along -x turned by the yaw);
on any bottom :func:`sim.dataset.randomization.resting_depth` gives the depth.

The meshes are built on first use and cached; ``trimesh`` is imported then, not with the
module (what imports :mod:`sim.scene.target_meshes` alone keeps its import time).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from scenarios.config.world import DEBRIS_DEFAULT_SIZES_M
from sim.scene.triangle_mesh import TriangleMesh

DEBRIS_SIZES_M: dict[str, tuple[float, float, float]] = DEBRIS_DEFAULT_SIZES_M  # the scenario's defaults
DEBRIS_SHAPES = tuple(DEBRIS_SIZES_M)


def debris_default_size_m(shape: str) -> tuple[float, float, float]:
    """The default ``(length, width, height)`` of a debris shape lying in its default
    orientation, m (an estimate of a common real object; the module's table).

    Raises:
        KeyError: not a debris shape (:data:`DEBRIS_SHAPES`).
    """
    return DEBRIS_SIZES_M[shape]


# --- closed parts (trimesh.Trimesh), built z up (x along the object, resting near z = 0) --------


def _outward(mesh):
    """``mesh`` with its faces wound outwards (positive volume)."""
    if mesh.volume < 0.0:
        mesh.invert()
    return mesh


def _rotation(angle_rad: float, axis) -> NDArray[np.float64]:
    import trimesh

    return trimesh.transformations.rotation_matrix(angle_rad, axis)


def _revolved_along_x(profile_rz, sections: int = 32, section_scale_yz: tuple[float, float] = (1.0, 1.0)):
    """Closed solid of revolution about local x from a (radius, axial) profile that starts and
    ends on the axis (axial 0 at -x); its section scaled by ``section_scale_yz`` (an ellipse)."""
    import trimesh

    mesh = trimesh.creation.revolve(np.asarray(profile_rz, dtype=np.float64), sections=sections)
    mesh.apply_transform(_rotation(0.5 * np.pi, [0.0, 1.0, 0.0]))  # revolution axis z -> x
    if section_scale_yz != (1.0, 1.0):
        mesh.apply_transform(np.diag([1.0, section_scale_yz[0], section_scale_yz[1], 1.0]))
    return _outward(mesh)


def _cylinder(radius: float, a, b, sections: int = 32):
    """Closed cylinder from point ``a`` to point ``b``."""
    import trimesh

    return _outward(trimesh.creation.cylinder(radius=radius, segment=np.array([a, b], dtype=np.float64),
                                              sections=sections))


def _loft(rings: NDArray[np.float64], closed: bool):
    """Closed surface through ``rings`` ((m, k, 3): m cross-sections of k points each, all in
    the same sense): quads between consecutive rings; ``closed`` joins the last ring to the
    first (a ring tube), else each end ring is capped by a fan about its centroid (convex
    sections)."""
    import trimesh

    m, k, _ = rings.shape
    i = np.arange(m if closed else m - 1)[:, None]
    j = np.arange(k)[None, :]
    a, b = i * k + j, i * k + (j + 1) % k
    c, d = ((i + 1) % m) * k + j, ((i + 1) % m) * k + (j + 1) % k
    faces = [np.stack([a, b, d], axis=-1).reshape(-1, 3), np.stack([a, d, c], axis=-1).reshape(-1, 3)]
    vertices = [rings.reshape(-1, 3)]
    if not closed:
        start, end = m * k, m * k + 1
        vertices.append(np.stack([rings[0].mean(axis=0), rings[-1].mean(axis=0)]))
        jj = np.arange(k)
        faces.append(np.stack([np.full(k, start), (jj + 1) % k, jj], axis=-1))
        faces.append(np.stack([np.full(k, end), (m - 1) * k + jj, (m - 1) * k + (jj + 1) % k], axis=-1))
    mesh = trimesh.Trimesh(np.concatenate(vertices), np.concatenate(faces), process=False)
    return _outward(mesh)


def _tube(path_xy, radius, sides: int = 12, closed: bool = False):
    """Round bar of ``radius`` (scalar or one per point) along a polyline in the xy plane, closed
    into a ring or capped at both ends. ``sides`` a multiple of 4 puts a vertex on the bar's top
    and bottom (the bar lies flat on z = -radius .. +radius)."""
    p = np.c_[np.asarray(path_xy, dtype=np.float64), np.zeros(len(path_xy))]
    seg = (np.roll(p, -1, axis=0) - p) if closed else np.diff(p, axis=0)
    seg /= np.linalg.norm(seg, axis=1, keepdims=True)
    if closed:
        t = seg + np.roll(seg, 1, axis=0)
    else:
        t = np.vstack([seg[:1], seg[:-1] + seg[1:], seg[-1:]])
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    n = np.c_[-t[:, 1], t[:, 0], np.zeros(len(t))]  # in-plane normal; the binormal is z
    phi = 2.0 * np.pi * np.arange(sides) / sides
    r = np.broadcast_to(np.asarray(radius, dtype=np.float64), (len(p),))
    rings = (p[:, None, :] + r[:, None, None] * (np.cos(phi)[None, :, None] * n[:, None, :]
                                                 + np.sin(phi)[None, :, None] * np.array([0.0, 0.0, 1.0])))
    return _loft(rings, closed)


# --- the objects: lists of closed parts, at their real size, metres ------------------------------


def _bottle():
    """1 l PET drink bottle, 0.25 m long, 80 mm across; base at axial 0 (local -x)."""
    u = np.linspace(0.0, 1.0, 9)[1:-1]
    shoulder = [(0.0135 + 0.0265 * (0.5 + 0.5 * np.cos(np.pi * s)), 0.15 + 0.05 * s) for s in u]
    profile = ([(0.0, 0.004), (0.02, 0.0015), (0.03, 0.0), (0.036, 0.0005), (0.0392, 0.003), (0.04, 0.008),
                (0.04, 0.15)] + shoulder
               + [(0.0135, 0.2), (0.0135, 0.208), (0.0175, 0.208), (0.0175, 0.211), (0.0135, 0.211),
                  (0.0135, 0.214), (0.0155, 0.214), (0.0155, 0.248), (0.0145, 0.25), (0.0, 0.25)])
    return [_revolved_along_x(profile)]


def _can():
    """330-355 ml drink can, 0.12 m long, 66 mm across."""
    profile = [(0.0, 0.009), (0.015, 0.0075), (0.022, 0.004), (0.025, 0.0), (0.0268, 0.0), (0.0285, 0.002),
               (0.031, 0.006), (0.033, 0.012), (0.033, 0.104), (0.0295, 0.112), (0.0285, 0.1145),
               (0.0295, 0.115), (0.0297, 0.1185), (0.0285, 0.12), (0.0268, 0.12), (0.0262, 0.1165),
               (0.025, 0.1155), (0.0, 0.1155)]
    return [_revolved_along_x(profile)]


def _chain(n_links: int = 9, d: float = 0.0155):
    """``n_links`` oval links of wire diameter ``d`` (5 d long, 3.35 d wide outside, pitch 3 d);
    the middle link and every second one from it on edge, the others flat."""
    s, rc = 0.825 * d, 1.175 * d  # half the straight length, the end arcs' centreline radius
    a = np.linspace(-0.5 * np.pi, 0.5 * np.pi, 12)
    path = np.vstack([np.c_[s + rc * np.cos(a), rc * np.sin(a)], np.c_[-s - rc * np.cos(a), -rc * np.sin(a)]])
    on_edge = _rotation(0.5 * np.pi, [1.0, 0.0, 0.0])
    parts = []
    for k in range(n_links):
        link = _tube(path, 0.5 * d, sides=12, closed=True)
        if (k - n_links // 2) % 2 == 0:
            link.apply_transform(on_edge)
        link.apply_translation([3.0 * d * k, 0.0, 0.0])
        parts.append(link)
    return parts


def _drink_carton():
    """1 l brick carton, 0.2 m long with its cap, lying on its broad face; its top end at +x."""
    import trimesh

    brick = trimesh.creation.box(extents=[0.188, 0.095, 0.07])
    brick.apply_translation([-0.006, 0.0, 0.035])  # x -0.1 .. 0.088
    fin = trimesh.creation.box(extents=[0.006, 0.088, 0.004])  # the top seal, standing 2 mm proud
    fin.apply_translation([0.087, 0.0, 0.063])
    cap = _cylinder(0.0125, [0.086, 0.02, 0.03], [0.1, 0.02, 0.03])
    return [_outward(brick), _outward(fin), cap]


def _hook():
    """12 mm round bar bent into a J: shank along +x from an eye ring, a 26 mm bend to -y and a
    point tapered back along -x; lying flat."""
    import trimesh

    r, eye_r, bend_r, shank, tip = 0.006, 0.016, 0.026, 0.08, 0.035
    a = np.linspace(0.5 * np.pi, -0.5 * np.pi, 17)[1:]
    path = np.vstack([np.c_[np.linspace(-0.5 * r, shank, 5), np.zeros(5)],
                      np.c_[shank + bend_r * np.cos(a), -bend_r + bend_r * np.sin(a)],
                      np.c_[np.linspace(shank, shank - tip, 5)[1:], np.full(4, -2.0 * bend_r)]])
    radius = np.full(len(path), r)
    radius[-4:] = r * np.linspace(0.85, 0.35, 4)  # the point
    eye = trimesh.creation.torus(major_radius=eye_r, minor_radius=r, major_sections=24, minor_sections=12)
    eye.apply_translation([-eye_r, 0.0, 0.0])
    return [_tube(path, radius, sides=12), _outward(eye)]


def _propeller(n_blades: int = 3, tip_r: float = 0.15, pitch: float = 0.18, hub_h: float = 0.06):
    """``n_blades`` twisted blades on a tapered hub lying on its end; one blade along +x."""
    hub = _revolved_along_x([(0.0, 0.0), (0.032, 0.0), (0.032, 0.004), (0.028, hub_h), (0.0, hub_h)])
    hub.apply_transform(_rotation(-0.5 * np.pi, [0.0, 1.0, 0.0]))  # axis x -> z, base at z = 0
    root_r = 0.02
    s = np.linspace(0.0, 1.0, 12)
    r = root_r + s * (tip_r - root_r)
    chord = 0.012 + 0.078 * np.sin(np.pi * (0.1 + 0.9 * s)) ** 0.6
    thick = 0.010 - 0.007 * s
    beta = np.arctan(pitch / (2.0 * np.pi * r))  # the blade angle of a constant geometric pitch
    th = 2.0 * np.pi * np.arange(12) / 12
    xi = 0.5 * chord[:, None] * np.cos(th)[None, :]  # along the chord
    eta = 0.5 * thick[:, None] * np.sin(th)[None, :]  # across it
    cb, sb = np.cos(beta)[:, None], np.sin(beta)[:, None]
    rings = np.stack([np.broadcast_to(r[:, None], xi.shape), xi * cb - eta * sb,
                      0.5 * hub_h + xi * sb + eta * cb], axis=-1)
    blade = _loft(rings, closed=False)
    parts = [hub]
    for k in range(n_blades):
        b = blade.copy()
        b.apply_transform(_rotation(2.0 * np.pi * k / n_blades, [0.0, 0.0, 1.0]))
        parts.append(b)
    return parts


def _shampoo_bottle():
    """Shampoo bottle, 0.2 m long with its cap, 80 x 45 mm elliptical section, lying flat."""
    u = np.linspace(0.0, 1.0, 7)[1:-1]
    shoulder = [(0.012 + 0.028 * (0.5 + 0.5 * np.cos(np.pi * s)), 0.14 + 0.03 * s) for s in u]
    body = ([(0.0, 0.0), (0.03, 0.0), (0.037, 0.002), (0.04, 0.008), (0.04, 0.14)] + shoulder
            + [(0.012, 0.17), (0.012, 0.176), (0.0, 0.176)])
    cap = [(0.0, 0.172), (0.017, 0.172), (0.017, 0.196), (0.0155, 0.2), (0.0, 0.2)]
    return [_revolved_along_x(body, section_scale_yz=(1.0, 0.5625)),
            _revolved_along_x(cap, section_scale_yz=(1.0, 0.75))]


def _valve():
    """Flanged gate valve standing on its flanges: 0.2 m face to face, 100 mm flanges, body
    along x, bonnet, stem and a hand-wheel (ring, hub, three spokes) 0.12 m up."""
    import trimesh

    axis_z, wheel_z, tube = 0.05, 0.1145, 0.0055
    parts = [_cylinder(0.035, [-0.04, 0.0, axis_z], [0.04, 0.0, axis_z]),  # body
             _cylinder(0.027, [-0.09, 0.0, axis_z], [0.09, 0.0, axis_z]),  # the pipe ends
             _cylinder(0.05, [-0.1, 0.0, axis_z], [-0.086, 0.0, axis_z]),  # flanges
             _cylinder(0.05, [0.086, 0.0, axis_z], [0.1, 0.0, axis_z]),
             _cylinder(0.026, [0.0, 0.0, axis_z], [0.0, 0.0, 0.082]),  # bonnet
             _cylinder(0.032, [0.0, 0.0, 0.078], [0.0, 0.0, 0.086]),  # bonnet flange
             _cylinder(0.006, [0.0, 0.0, 0.084], [0.0, 0.0, wheel_z], sections=12),  # stem
             _cylinder(0.011, [0.0, 0.0, wheel_z - tube], [0.0, 0.0, wheel_z + tube], sections=16)]  # hub
    wheel = trimesh.creation.torus(major_radius=0.038, minor_radius=tube, major_sections=32, minor_sections=8)
    wheel.apply_translation([0.0, 0.0, wheel_z])
    parts.append(_outward(wheel))
    for k in range(3):
        ang = 0.5 * np.pi + 2.0 * np.pi * k / 3
        parts.append(_cylinder(0.0035, [0.0, 0.0, wheel_z],
                               [0.038 * np.cos(ang), 0.038 * np.sin(ang), wheel_z], sections=8))
    return parts


_BUILDERS = {"bottle": _bottle, "can": _can, "chain": _chain, "drink_carton": _drink_carton, "hook": _hook,
             "propeller": _propeller, "shampoo_bottle": _shampoo_bottle, "valve": _valve}


@lru_cache(maxsize=len(_BUILDERS))
def _unit_mesh(shape: str) -> tuple[NDArray[np.float64], NDArray[np.int64], tuple[float, float, float]]:
    """The parts of ``shape`` concatenated (each keeps its own vertices), scaled into the unit box
    centred on x and y with its base on z = 0, in the NED-aligned frame (z down: turned half a
    turn about x, a rotation, so the winding stays outward); and its real size (length, width,
    height), m."""
    parts = _BUILDERS[shape]()
    offsets = np.cumsum([0] + [len(p.vertices) for p in parts])
    v = np.concatenate([np.asarray(p.vertices, dtype=np.float64) for p in parts])
    f = np.concatenate([np.asarray(p.faces, dtype=np.int64) + o for p, o in zip(parts, offsets)])
    lo, hi = v.min(axis=0), v.max(axis=0)
    extent = hi - lo
    unit = (v - np.array([0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), lo[2]])) / extent
    unit[:, 1:] *= -1.0  # z up -> z down (and y with it: a half turn about x)
    unit.setflags(write=False)
    f.setflags(write=False)
    return unit, f, (float(extent[0]), float(extent[1]), float(extent[2]))


@lru_cache(maxsize=128)
def debris_mesh(shape: str, size_m: tuple[float, float, float]) -> TriangleMesh:
    """The closed mesh of debris ``shape`` scaled to the box ``size_m`` (length, width, height,
    m): centred on local x and y, base on z = 0, top at z = -height (read-only arrays, shared).

    Raises:
        ValueError: not a debris shape, or a size that is not three positive lengths.
    """
    if shape not in _BUILDERS:
        raise ValueError(f"unknown debris shape {shape!r}; one of {', '.join(DEBRIS_SHAPES)}")
    size = np.asarray(size_m, dtype=np.float64)
    if size.shape != (3,) or not np.all(size > 0.0):
        raise ValueError(f"debris size_m must be three positive lengths, got {size_m}")
    unit, faces, _ = _unit_mesh(shape)
    mesh = TriangleMesh(unit * size, faces.copy())
    mesh.vertices.setflags(write=False)
    mesh.faces.setflags(write=False)
    return mesh


def debris_mesh_arrays(shape: str, size_m: tuple[float, float, float]) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """:func:`debris_mesh`'s vertices (n, 3) and faces (m, 3), read-only."""
    mesh = debris_mesh(shape, tuple(float(x) for x in size_m))
    return mesh.vertices, mesh.faces


def debris_real_size_m(shape: str) -> tuple[float, float, float]:
    """The box of ``shape`` as built, at its real proportions, before scaling (m): the default
    sizes are these, rounded to the millimetre (a test keeps them so)."""
    return _unit_mesh(shape)[2]
