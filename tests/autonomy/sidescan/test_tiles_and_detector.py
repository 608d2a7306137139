"""Onboard side-scan tiles (timing, geometry by hand) and the highlight-shadow detector on pings
rendered by the analytic caster (a box on a flat seabed: its true position is known exactly)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.frames import rot_from_euler
from autonomy.messages import NavEstimate, SssPing
from autonomy.sidescan.config import SssDetectorConfig
from autonomy.sidescan.detector import SssHighlightShadowDetector
from autonomy.sidescan.tile_assembler import SssTileAssembler
from scenarios.config.sss import SssConfig
from sim.sensors.analytic_caster import AnalyticBox, AnalyticCaster
from sim.sensors.sss import SssSensor
from tests.support import SceneObj


def nav(t: float, n: float, e: float, psi: float) -> NavEstimate:
    z = np.zeros(3)
    return NavEstimate(t, np.array([n, e, 10.0]), np.array([0.0, 0.0, psi]), z, z, np.eye(3))


def ping(t: float, n_bins: int = 8) -> SssPing:
    return SssPing(t, np.zeros((2, n_bins), np.uint8), 0.5, 5.0, ground_lines_u8=np.full((2, n_bins), 7, np.uint8))


def test_tile_every_period_holds_the_pings_of_its_interval():
    rate, period = 15.0, 2.0
    asm = SssTileAssembler(period)
    tiles = []
    for k in range(1, 100):
        t = k / rate
        out = asm.add(ping(t), nav(t, 0.0, 1.5 * t, 0.5 * np.pi))
        if out is not None:
            tiles.append((t, out))
    assert [tile.index for _, tile in tiles] == [1, 2, 3]
    for (t_emit, tile) in tiles:
        k = tile.index
        # closed by the first ping after k T, holding exactly the pings in ((k-1) T, k T]
        assert k * period < t_emit <= k * period + 1.0 / rate + 1e-9
        expect = [j / rate for j in range(1, 100) if (k - 1) * period < j / rate <= k * period + 1e-9]
        np.testing.assert_allclose(tile.ping_t_s, expect)
        assert tile.image.shape == (2, len(expect), 8) and tile.ground_range
        assert tile.t_s == pytest.approx(expect[-1])


def test_tile_geometry_heading_east():
    asm = SssTileAssembler(1.0)
    for k in range(11):  # 10 Hz, 1.5 m/s east; pose at the ping
        t = 0.1 * k
        asm.add(ping(t), nav(t, 3.0, 1.5 * t, 0.5 * np.pi))
    tile = asm.add(ping(1.05), nav(1.05, 3.0, 1.575, 0.5 * np.pi))
    # starboard of an east heading is south; ground range of column 9 is 9.5 * 0.5 m
    ned = tile.to_ned(np.array([1, 0]), np.array([4.0, 4.0]), np.array([9.0, 9.0]))
    e4 = 1.5 * tile.ping_t_s[4]
    np.testing.assert_allclose(ned, [[3.0 - 4.75, e4], [3.0 + 4.75, e4]])
    ell = tile.to_tile_frame(ned)
    along = e4 - 1.5 * tile.ping_t_s[-1]
    np.testing.assert_allclose(ell, [[along, 4.75], [along, -4.75]], atol=1e-12)


SEABED_M, DEPTH_M, SPEED, RATE = 20.0, 12.0, 1.0, 10.0


def fly(caster, objects, n_pings: int, seed: int):
    """Pings along north at SPEED from the origin, exact poses, into one tile."""
    cfg = SssConfig(range_max_m=40.0, n_bins=600, elevation_rays=32, ground_range=True, gain_db=-10.0,
                    rate_hz=RATE)
    sonar = SssSensor(cfg, (0.0, 0.0, 0.0), np.random.default_rng(seed))
    asm = SssTileAssembler(n_pings / RATE)
    tile = None
    for k in range(1, n_pings + 2):
        t = k / RATE
        pos = np.array([SPEED * t, 0.0, DEPTH_M])
        r = sonar.render(t, pos, rot_from_euler(0.0, 0.0, 0.0), caster, objects)
        tile = asm.add(r.ping, nav(t, pos[0], pos[1], 0.0)) or tile
    return tile


def test_detector_finds_a_box_where_it_lies_and_nothing_on_bare_seabed():
    centre = np.array([12.0, 22.0, SEABED_M - 0.3])  # 22 m to starboard, 0.6 m high
    box = AnalyticBox(centre, np.array([1.0, 0.4, 0.3]), 0)
    caster = AnalyticCaster(SEABED_M, boxes=(box,))
    det = SssHighlightShadowDetector(SssDetectorConfig())
    tile = fly(caster, [SceneObj(0, "b", "mine_like", True, centre)], 250, seed=3)
    out = det.detect(tile)
    assert len(out.ell_m) == 1
    truth = tile.to_tile_frame(centre[:2][None])[0]  # exact poses: the tile frame is the true one
    assert truth[0] == pytest.approx(12.0 - SPEED * tile.ping_t_s[-1]) and truth[1] == pytest.approx(22.0)
    # the highlight is the box's facing side, 0.4 m before its centre in range
    assert np.linalg.norm(out.ell_m[0] - truth) < 1.0
    assert 1.4 <= out.length_m[0] <= 2.1 and out.pi1[0] > 0.5  # 2 m long; the beam trims its ends
    bare = [det.detect(fly(AnalyticCaster(SEABED_M), [], 250, seed=s)) for s in range(3)]
    assert sum(len(b.ell_m) for b in bare) == 0


IMU_HZ, PING_HZ, CRUISE = 50.0, 15.0, 0.85


def nav_of_last_imu(t: float, speed: float) -> NavEstimate:
    """The filter's estimate when a ping taken at ``t`` is handed over: exact, but of the time
    of the last IMU message (50 Hz), up to 20 ms before the ping; heading north at ``speed``."""
    t_nav = math.floor(t * IMU_HZ + 1e-9) / IMU_HZ
    return NavEstimate(t_nav, np.array([speed * t_nav, 0.0, DEPTH_M]), np.zeros(3), np.array([speed, 0.0, 0.0]),
                       np.zeros(3), np.eye(3))


def test_rows_are_posed_at_the_ping_time_not_the_filter_time():
    # 15 pings/s at 0.85 m/s: rows 5.67 cm apart, whatever the filter's time at each ping
    asm = SssTileAssembler(4.0)
    tile = None
    for k in range(1, 80):
        t = k / PING_HZ
        tile = asm.add(ping(t), nav_of_last_imu(t, CRUISE)) or tile
    step = np.linalg.norm(np.diff(tile.pos_ne, axis=0), axis=1)
    assert np.median(step) == pytest.approx(CRUISE / PING_HZ, rel=0.02)
    np.testing.assert_allclose(tile.pos_ne[:, 0], CRUISE * tile.ping_t_s, rtol=0, atol=1e-12)


def test_a_2m_box_measures_the_same_length_with_the_filter_of_the_last_imu_message():
    centre = np.array([10.0, 22.0, SEABED_M - 0.3])  # 2 m along track, 22 m to starboard
    caster = AnalyticCaster(SEABED_M, boxes=(AnalyticBox(centre, np.array([1.0, 0.4, 0.3]), 0),))
    cfg = SssConfig(range_max_m=40.0, n_bins=600, elevation_rays=32, ground_range=True, gain_db=-10.0,
                    rate_hz=PING_HZ)
    det = SssHighlightShadowDetector(SssDetectorConfig())
    lengths = {}
    for how in ("exact", "last_imu"):
        sonar = SssSensor(cfg, (0.0, 0.0, 0.0), np.random.default_rng(3))
        n_pings = 300
        asm, tile = SssTileAssembler(n_pings / PING_HZ), None
        for k in range(1, n_pings + 2):
            t = k / PING_HZ
            pos = np.array([CRUISE * t, 0.0, DEPTH_M])
            r = sonar.render(t, pos, rot_from_euler(0.0, 0.0, 0.0), caster, [SceneObj(0, "b", "mine_like", True, centre)])
            nav_t = nav(t, pos[0], pos[1], 0.0) if how == "exact" else nav_of_last_imu(t, CRUISE)
            tile = asm.add(r.ping, nav_t) or tile
        out = det.detect(tile)
        assert len(out.length_m) == 1, how
        lengths[how] = float(out.length_m[0])
    assert 1.6 <= lengths["exact"] <= 2.1
    assert lengths["last_imu"] == pytest.approx(lengths["exact"], rel=0.02)
