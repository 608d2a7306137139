"""SPA mapper on a two-lane out-and-back survey: objects seen from both lanes end as one
confirmed object each (paper 003, Sections IV-C to IV-F), with the true state and with the SPA
vehicle belief."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.mapping.config import SpaMapperConfig
from autonomy.mapping.spa_mapper import SpaMapper, rotate_to_local
from sim.mcm.survey import LawnmowerPath, McmSurveyConfig

SPEED, T_TILE = 1.5, 33.0
OBJECTS = np.array([[60.0, 45.0], [110.0, 70.0], [160.0, 40.0], [210.0, 90.0], [260.0, 55.0],
                    [310.0, 75.0], [60.0, -50.0], [160.0, -80.0], [260.0, -60.0], [340.0, -45.0]])


PATH = LawnmowerPath(McmSurveyConfig(n_lanes=2, area_side_m=360.0, lane_spacing_m=20.0, first_lane_east_m=0.0,
                                     speed_mps=SPEED))
LEG_S = 360.0 / SPEED  # end of the way out (north along east 0); a half circle, then south along east 20


def _state(t: float) -> np.ndarray:
    return PATH.state(np.array([t]))[0]


def _detections(cfg: SpaMapperConfig, s: np.ndarray, rng: np.random.Generator):
    psi = np.arctan2(s[3], s[2])
    loc = rotate_to_local(OBJECTS - s[:2], np.full(len(OBJECTS), psi))
    a = np.abs(loc[:, 1])
    inside = (loc[:, 0] >= -cfg.tile_length_m) & (loc[:, 0] <= 0) & (a >= cfg.tile_near_m) & (
        a <= cfg.tile_near_m + cfg.tile_width_m)
    ell = loc[inside] + cfg.sigma_meas_m * rng.standard_normal((int(inside.sum()), 2))
    return ell, rng.beta(2.0, 6.0, int(inside.sum()))


def _run(mode: str, ins_offset_east_m: float, seed: int = 0):
    """Out and back; the INS is exact on the way out and ``ins_offset_east_m`` off (east) after the
    turn. Returns the mapper and the vehicle errors (m) at the tiles after the turn."""
    # the paper's process noise (a smaller one cannot follow the 8.6 deg/s turn and leaves the
    # belief metres off after it); the exact INS is trusted only to 10 m
    cfg = SpaMapperConfig(mode=mode, n_particles=400, pd=1.0, nav_floor_pos_m=5.0, nav_floor_heading_deg=1.0)
    rng = np.random.default_rng(seed)
    m = SpaMapper(cfg, _state(0.0), np.random.default_rng(seed + 100), initial_std=(0.3, 0.3, 0.02, 0.02, 1e-4))
    errs = []
    for k in range(1, int(PATH.duration_s // T_TILE) + 1):
        t_tile = k * T_TILE
        for t in np.arange(t_tile - T_TILE + 1.0, t_tile + 0.5):
            s = _state(t)
            off = ins_offset_east_m if t > LEG_S + 25.0 else 0.0
            m.nav_update(float(t), [s[0], s[1] + off, np.arctan2(s[3], s[2])])
        s = _state(t_tile)
        m.set_true_state(s)
        m.tile_update(*_detections(cfg, s, rng))
        if t_tile > LEG_S + 25.0:
            errs.append(float(np.linalg.norm(m.vehicle_estimate()[:2] - s[:2])))
    return m, np.array(errs)


def _check_map(m: SpaMapper) -> int:
    """One confirmed object per true one, each within 3 m; returns how many are confirmed."""
    est = m.estimate()
    d = np.linalg.norm(est.pos_ned[:, None] - OBJECTS[None], axis=-1)
    nearest = d.argmin(axis=1)
    assert len(set(nearest.tolist())) == len(nearest)  # no duplicate after the second pass
    assert d.min(axis=1).max() < 3.0
    return len(est.pos_ned)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_two_passes_over_each_object_yield_one_object_each(seed):
    # every object is seen from both lanes (the last one only near the turn, one on the edge of a
    # tile): the clairvoyant mapper confirms at least 9; the SPA belief (exact INS trusted to
    # 10 m) at most one fewer on a seed, with no duplicate (before the fixes: 3-7, 1 m-off maps)
    n_true_state = _check_map(_run("clairvoyant", 0.0, seed)[0])
    assert n_true_state >= len(OBJECTS) - 1
    m, errs = _run("spa", 0.0, seed)
    assert _check_map(m) >= n_true_state - 1
    assert np.sqrt(np.mean(errs ** 2)) < 5.0
