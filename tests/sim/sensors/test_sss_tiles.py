"""Side-scan tiles: an object's box from a waterfall on the analytic caster, and the export."""

from __future__ import annotations

import json

import numpy as np
import pytest

from scenarios.config.sss import SssConfig
from sim.sensors.analytic_caster import AnalyticCaster, AnalyticSphere
from sim.sensors.sss import SssSensor, Waterfall
from sim.dataset.sss_tiles import cut_tiles, pings_per_tile, write_tiles
from tests.support import SceneObj


def test_sphere_box_in_a_waterfall_tile(tmp_path):
    s = SssSensor(SssConfig(speckle="none", range_max_m=60.0, n_bins=800), (0, 0, 0), np.random.default_rng(2))
    centre = np.array([10.0, -30.0, 29.0])  # 30 m to port, 10 m along track
    caster = AnalyticCaster(30.0, spheres=(AnalyticSphere(centre, 1.0, 4),))
    n = pings_per_tile(20.0, 1.5, s.rate_hz)  # 20 m tile
    step = 1.5 / s.rate_hz
    wf = Waterfall(s.n_bins)
    xs = np.arange(n) * step
    for x in xs:
        wf.add(s.render(0.0, np.array([x, 0.0, 10.0]), np.eye(3), caster, [SceneObj(4, "s", "mine", True, centre)],
                        noise=False))
    (tile,) = cut_tiles(wf.image(), wf.labels(), n)
    x0, y0, x1, y1 = tile.boxes[4]
    # rows: the pings whose beam plane (zero along-track width) cuts the sphere, |x - 10| < 1
    cut = np.flatnonzero(np.abs(xs - centre[0]) < 1.0)
    assert y0 == pytest.approx(cut[0], abs=1) and y1 - 1 == pytest.approx(cut[-1], abs=1)
    # columns: port is mirrored; the nearest slant range is seen at the closest ping
    r_near = np.hypot(30.0, 19.0) - 1.0
    assert x1 - 1 == s.n_bins - 1 - int(np.floor(r_near / s.bin_size_m))
    coco = write_tiles(tmp_path, [tile], {4: "mine"}, ["mine", "rock"])
    doc = json.loads(coco.read_text())
    assert doc["annotations"][0]["bbox"] == [x0, y0, x1 - x0, y1 - y0] and doc["annotations"][0]["category_id"] == 1
    assert (tmp_path / "labels" / "sss_000000.txt").read_text().startswith("0 ")


def test_tile_length_checks():
    assert pings_per_tile(50.0, 1.5, 10.0) == 333
    with pytest.raises(ValueError):
        pings_per_tile(0.01, 1.5, 10.0)
