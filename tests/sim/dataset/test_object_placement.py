"""Every generated object rests on the seabed under it: lowest point at the bed, or buried by
at most the drawn fraction of its height, checked on the compiled MuJoCo scene."""

from __future__ import annotations

import numpy as np
import pytest

from scenarios.config.world import WorldConfig
from scenarios.schema import Scenario
from sim.dataset import generate as gen
from sim.dataset.randomization import HELDOUT_RANDOMIZATION, TRAIN_RANDOMIZATION, WIDE_RANDOMIZATION
from sim.scene.world import build_world


def _world_vertices(model, data, gid: int) -> np.ndarray:
    mid = model.geom_dataid[gid]
    start, n = model.mesh_vertadr[mid], model.mesh_vertnum[mid]
    v = model.mesh_vert[start:start + n].astype(float)
    return data.geom_xpos[gid] + v @ data.geom_xmat[gid].reshape(3, 3).T


@pytest.mark.parametrize("rz", [TRAIN_RANDOMIZATION, WIDE_RANDOMIZATION, HELDOUT_RANDOMIZATION],
                         ids=["train", "wide", "heldout"])
def test_objects_rest_on_the_seabed(rz):
    max_burial = rz.burial_fraction[1]
    penetration, kinds = [], []
    for index in range(12):
        spec = gen.scene_spec(11, index, rz)
        scn = Scenario(name="placement", seed=spec.world_seed,
                       world=WorldConfig(seabed=spec.seabed, basin=spec.basin, targets=spec.targets))
        world = build_world(scn, with_vehicle=False)
        for obj, cfg in zip(world.objects, spec.targets):
            v = _world_vertices(world.model, world.data, obj.geom_id)
            below = v[:, 2] - world.seabed.depth_at(v[:, 0], v[:, 1])  # > 0: under the bed surface
            extent = np.ptp(v[:, 2])
            deepest = float(below.max())
            assert deepest >= -1e-6, f"{cfg.name} ({cfg.class_name}) floats {-deepest:.3f} m above the bed"
            assert deepest <= max_burial * extent + 1e-6, (
                f"{cfg.name} ({cfg.class_name}) buried {deepest:.3f} m of its {extent:.3f} m height")
            penetration.append(deepest / extent)
            kinds.append(cfg.class_name)
    penetration = np.array(penetration)
    kinds = np.array(kinds)
    assert "debris" in kinds and "rock" in kinds and "opi" in kinds
    assert np.mean(penetration < 1e-6) > 0.4  # most rest on the bed (burial is drawn 30 % of the time)
    assert (penetration > 0.02).any()  # and some are partly buried
    assert (penetration[kinds == "debris"] < max_burial + 1e-6).all()
