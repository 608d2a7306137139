"""SeabedConfig.depth_m is the depth at the patch centre center_ne_m, in the lookup and in the scene."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from scenarios import load_scenario
from sim.scene.seabed import make_seabed
from sim.scene.world import build_world


@pytest.mark.parametrize("az_deg", [0.0, 60.0, 200.0])
def test_depth_m_is_the_depth_at_the_patch_centre(az_deg):
    """A 3 deg slope centred at (-4, 17): depth_m there; at the NED origin, 4 m plus the slope's
    rise over the 4 m north / -17 m east offset along the downhill azimuth."""
    over = ["world.seabed.kind=slope", "world.seabed.slope_deg=3", f"world.seabed.slope_azimuth_deg={az_deg}",
            "world.seabed.center_ne_m=[-4.0, 17.0]", "world.seabed.depth_m=4.0", "world.basin.shape=none",
            "world.targets=[]"]
    scn = load_scenario("cssn_lawnmower", over)
    bed = make_seabed(scn.world.seabed, np.random.default_rng(0))
    a = np.deg2rad(az_deg)
    at_origin = 4.0 + np.tan(np.deg2rad(3.0)) * (4.0 * np.cos(a) - 17.0 * np.sin(a))
    assert float(bed.depth_at(-4.0, 17.0)) == pytest.approx(4.0, abs=1e-12)
    assert float(bed.depth_at(0.0, 0.0)) == pytest.approx(at_origin, abs=1e-12)
    world = build_world(scn, with_vehicle=False)
    for (n, e), want in [((-4.0, 17.0), 4.0), ((0.0, 0.0), at_origin)]:
        gid, dist = np.zeros(1, np.int32), np.zeros(1)
        mujoco.mj_multiRay(world.model, world.data, np.array([n, e, 0.0]), np.array([0.0, 0.0, 1.0]),
                           world.acoustic_geomgroup, 1, -1, gid, dist, None, 1, 100.0)
        assert dist[0] == pytest.approx(want, abs=1e-6)
