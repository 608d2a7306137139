"""The terrain slab mesh is wound outward by construction (trimesh as the oracle), so it
needs no normal repair: what ``trimesh.repair.fix_normals`` would do leaves it unchanged."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from sim.dataset.generate import scene_spec
from sim.dataset.randomization import TRAIN_RANDOMIZATION, WIDE_RANDOMIZATION
from sim.rng import component_rng
from sim.scene.seabed import make_seabed


def _mesh_beds():
    beds = []
    for rz in (TRAIN_RANDOMIZATION, WIDE_RANDOMIZATION):
        for i in range(12):
            spec = scene_spec(7, i, rz)
            bed = make_seabed(spec.seabed, component_rng(spec.world_seed, "seabed"))
            if bed.is_mesh:
                beds.append(pytest.param(bed, id=f"{spec.seabed.kind}-{i}"))
    return beds[:6]


@pytest.mark.parametrize("bed", _mesh_beds())
def test_terrain_slab_is_closed_consistently_wound_and_outward(bed):
    mesh = bed.terrain_mesh()
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0.0
    # top faces point up (-z in NED)
    top = (mesh.vertices[mesh.faces][:, :, 2] < mesh.vertices[:, 2].max() - 0.5).all(axis=1)
    assert (mesh.face_normals[top, 2] < 0.0).all()
    repaired = mesh.copy()
    trimesh.repair.fix_normals(repaired)
    assert np.array_equal(repaired.faces, mesh.faces)


@pytest.mark.parametrize("bed", _mesh_beds()[:1])
def test_seabed_asset_compiles_to_the_mesh_of_its_arrays(bed):
    """The ``.msh`` asset path gives MuJoCo the same mesh as ``uservert`` / ``userface``."""
    import mujoco

    from sim.scene.world import _add_msh_asset

    mesh = bed.terrain_mesh()
    models = []
    for via_asset in (False, True):
        spec = mujoco.MjSpec()
        if via_asset:
            spec.add_mesh(name="m", file=_add_msh_asset(spec, "seabed", mesh.vertices, mesh.faces))
        else:
            spec.add_mesh(name="m", uservert=mesh.vertices.astype(np.float32).ravel(),
                          userface=mesh.faces.astype(np.int32).ravel())
        spec.worldbody.add_geom(name="g", type=mujoco.mjtGeom.mjGEOM_MESH, meshname="m", contype=0, conaffinity=0)
        models.append(spec.compile())
    a, b = models
    assert a.nmeshvert == len(mesh.vertices) > 0
    for field in ("mesh_vert", "mesh_face", "mesh_normal", "geom_pos", "geom_quat", "geom_rbound", "bvh_aabb"):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field


def test_build_world_leaves_mujocos_mesh_cache_empty():
    import mujoco

    from scenarios.config.world import WorldConfig
    from scenarios.schema import Scenario
    from sim.scene.world import build_world

    spec = scene_spec(0, 3, WIDE_RANDOMIZATION)  # a rippled (mesh) seabed
    assert spec.seabed.kind != "slope"
    build_world(Scenario(name="s", seed=spec.world_seed, world=WorldConfig(seabed=spec.seabed, basin=spec.basin,
                                                                        targets=spec.targets)), with_vehicle=False)
    assert mujoco.mj_getCacheSize(mujoco.mj_getCache()) == 0


def test_depth_lookup_equals_scipys_regular_grid_interpolator_bit_for_bit():
    """Bilinear inside the grid, linear extension outside, NaN for a NaN position: the values of
    ``RegularGridInterpolator(bounds_error=False, fill_value=None)`` (the oracle) to the last bit."""
    from scipy.interpolate import RegularGridInterpolator

    rng = np.random.default_rng(5)
    for bed in [p.values[0] for p in _mesh_beds()[:3]]:
        n, e, z = bed.grid_n_m, bed.grid_e_m, bed.depth_grid_m
        q = rng.uniform(n[0] - 5.0, n[-1] + 5.0, (3000, 2))
        q[:40, 0] = rng.choice(n, 40)  # on grid lines and at the last node
        q[40:80, 1] = rng.choice(e, 40)
        q[80], q[81], q[82] = (n[-1], e[-1]), (n[0], e[0]), (np.nan, e[3])
        ref = RegularGridInterpolator((n, e), z, bounds_error=False, fill_value=None)(q)
        got = bed.depth_at(q[:, 0], q[:, 1])
        assert np.array_equal(got, ref, equal_nan=True) and np.isnan(got[82])
        assert bed.depth_at(q[5, 0], q[5, 1]).shape == ()  # scalars in, a 0-d depth out


def test_depth_lookup_on_a_read_only_grid_falls_back_to_scipy():
    bed = _mesh_beds()[0].values[0]
    z = bed.depth_grid_m.copy()
    z.setflags(write=False)
    frozen = type(bed)(bed.cfg, bed.grid_n_m, bed.grid_e_m, z)
    from scipy.interpolate import RegularGridInterpolator

    q = np.array([[1.3, -2.7], [200.0, 0.0], [-3.1, 4.4]])
    ref = RegularGridInterpolator((bed.grid_n_m, bed.grid_e_m), z, bounds_error=False, fill_value=None)(q)
    assert np.array_equal(frozen.depth_at(q[:, 0], q[:, 1]), ref)
    np.testing.assert_allclose(bed.depth_at(q[:, 0], q[:, 1]), ref, rtol=1e-14)


def test_holed_grid_arrays_equal_trimeshs_unreferenced_vertex_removal():
    bed = _mesh_beds()[0].values[0]
    z = bed.depth_grid_m.copy()
    z[10:30, 40:] = np.nan
    holed = type(bed)(bed.cfg, bed.grid_n_m, bed.grid_e_m, z)
    verts, faces = holed.terrain_arrays()
    nn, ee = np.meshgrid(bed.grid_n_m, bed.grid_e_m, indexing="ij")
    ref = trimesh.Trimesh(np.c_[nn.ravel(), ee.ravel(), np.nan_to_num(z, nan=0.0).ravel()],
                          np.vstack(_cell_faces(z)), process=False)
    ref.remove_unreferenced_vertices()
    assert np.array_equal(verts, ref.vertices) and np.array_equal(faces, ref.faces)
    assert len(verts) < z.size and np.isfinite(verts).all()


def _cell_faces(z):
    nx, ny = z.shape
    idx = np.arange(nx * ny).reshape(nx, ny)
    ok = np.isfinite(z)
    cell = (ok[:-1, :-1] & ok[1:, :-1] & ok[1:, 1:] & ok[:-1, 1:]).ravel()
    a, b, c, d = (idx[:-1, :-1].ravel()[cell], idx[1:, :-1].ravel()[cell], idx[1:, 1:].ravel()[cell],
                  idx[:-1, 1:].ravel()[cell])
    return [np.c_[a, d, b], np.c_[b, d, c]]
