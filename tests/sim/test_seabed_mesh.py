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
