"""The terrain slab mesh is wound outward by construction (trimesh as the oracle), so it
needs no normal repair: what ``trimesh.repair.fix_normals`` would do leaves it unchanged."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from sim.dataset.generate import TRAIN_RANDOMIZATION, WIDE_RANDOMIZATION, scene_spec
from sim.rng import component_rng
from sim.seabed import make_seabed


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

    from sim.world import _add_msh_asset

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
    from sim.world import build_world

    spec = scene_spec(0, 3, WIDE_RANDOMIZATION)  # a rippled (mesh) seabed
    assert spec.seabed.kind != "slope"
    build_world(Scenario(name="s", seed=spec.world_seed, world=WorldConfig(seabed=spec.seabed, basin=spec.basin,
                                                                        targets=spec.targets)), with_vehicle=False)
    assert mujoco.mj_getCacheSize(mujoco.mj_getCache()) == 0
