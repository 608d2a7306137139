"""The vehicle particle filter's proposal (locally optimal given one INS output) against a
brute-force bootstrap oracle, and the tile update's effect on the vehicle belief."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.mapping.auv_motion import heading_rad, nct_predict, nct_predict_ins_proposal
from autonomy.mapping.config import SpaMapperConfig
from autonomy.mapping.spa_mapper import SpaMapper, beta_pdf

SIG_LIN, SIG_ANG = 0.5, np.deg2rad(20.0)  # paper 003's process noise at 1 Hz
VAR_P, VAR_H = 2.0 ** 2, np.deg2rad(2.0) ** 2
G = np.array([1.6, 0.3, np.deg2rad(8.0)])


def _bootstrap(state: np.ndarray, n: int, rng: np.random.Generator):
    """Prior draws (turn-rate noise at the start of the step, linear noise along the new heading)
    and their exact INS likelihoods, independent of the proposal's algebra."""
    u = rng.standard_normal((n, 2)) * [SIG_LIN, SIG_ANG]
    s = np.repeat(state[None], n, axis=0)
    s[:, 4] += u[:, 1]
    s = nct_predict(s, 1.0, 0.0, 0.0, rng)  # noise-free coordinated turn at the new rate
    psi = heading_rad(s)
    h = np.column_stack([np.cos(psi), np.sin(psi)])
    s[:, :2] += 0.5 * u[:, :1] * h
    s[:, 2:4] += u[:, :1] * h
    e_h = np.angle(np.exp(1j * (G[2] - heading_rad(s))))
    logl = -0.5 * (((s[:, :2] - G[:2]) ** 2).sum(1) / VAR_P + e_h ** 2 / VAR_H)
    return s, logl


@pytest.mark.parametrize("state", [[0.0, 0.0, 1.5, 0.0, 0.0], [0.5, -1.0, 1.4, 0.3, 0.1],
                                   [-1.0, 0.5, 0.4, 0.05, -0.05]])
def test_proposal_matches_prior_times_likelihood(state):
    # same posterior mean and the same evidence as the bootstrap filter, with far less degeneracy
    state = np.asarray(state)
    rng = np.random.default_rng(1)
    xb, logl = _bootstrap(state, 400_000, rng)
    wb = np.exp(logl)
    xp, logw = nct_predict_ins_proposal(np.repeat(state[None], 100_000, axis=0), 1.0, SIG_LIN, SIG_ANG, G,
                                        VAR_P, VAR_H, rng)
    wp = np.exp(logw)
    assert wp.mean() == pytest.approx(wb.mean(), rel=0.05)  # evidence p(g | s_prev), same constant
    mean_b, mean_p = wb @ xb / wb.sum(), wp @ xp / wp.sum()
    sd_b = np.sqrt(wb @ (xb - mean_b) ** 2 / wb.sum())
    assert np.all(np.abs(mean_p - mean_b) < 0.05 * sd_b + 1e-3)
    ess_b, ess_p = wb.sum() ** 2 / (wb ** 2).sum() / len(wb), wp.sum() ** 2 / (wp ** 2).sum() / len(wp)
    assert ess_p > 0.5 and ess_p > 5.0 * ess_b


def test_ins_filter_follows_an_exact_ins_through_a_turn():
    # half circle of radius 10 m at 1.5 m/s, then straight; INS exact, trusted to 1 m / 2 deg
    cfg = SpaMapperConfig(mode="ins_filter", n_particles=300)
    m = SpaMapper(cfg, [0.0, 0.0, 1.5, 0.0, 0.0], np.random.default_rng(3))
    rate = 0.15
    errs = []
    for t in range(1, 121):
        tt = min(t, 20.94)
        psi = rate * tt
        n_, e_ = np.sin(psi) / rate * 1.5 / 1.5 * 10.0 * rate, (1 - np.cos(psi)) * 10.0
        if t > 20.94:
            n_ += -1.5 * (t - 20.94)
        m.nav_update(float(t), [n_, e_, np.angle(np.exp(1j * psi))])
        errs.append(np.hypot(*(m.vehicle_estimate()[:2] - [n_, e_])))
    assert max(errs) < 2.0  # the bootstrap filter was 3-5 m off and stayed there


def test_tile_update_does_not_widen_the_heading_belief():
    # the INS pins the heading (45 deg +- 0.5) but not the speed (1.5 +- 0.6 m/s): a jitter of
    # the velocity components sized by their spread would turn the heading by degrees
    cfg = SpaMapperConfig(mode="spa", n_particles=2000)
    rng = np.random.default_rng(4)
    m = SpaMapper(cfg, [0.0, 0.0, 1.06, 1.06, 0.0], rng)
    speed = np.clip(1.5 + 0.6 * rng.standard_normal(cfg.n_particles), 0.3, None)
    psi = np.deg2rad(45.0 + 0.5 * rng.standard_normal(cfg.n_particles))
    m.S[:, 2], m.S[:, 3] = speed * np.cos(psi), speed * np.sin(psi)
    obj_ned = np.array([-25.0 * np.cos(np.pi / 4) - 60.0 * np.sin(np.pi / 4),
                        -25.0 * np.sin(np.pi / 4) + 60.0 * np.cos(np.pi / 4)])  # 25 m behind, 60 m starboard
    m.r = np.array([0.9])
    m.X = (obj_ned + 0.5 * rng.standard_normal((cfg.n_particles, 2)))[None]
    m.W = np.full((1, cfg.n_particles, 2), 0.5 / cfg.n_particles)
    before = np.std(heading_rad(m.S))
    m.tile_update([[-25.0, 60.0]], [0.5])
    assert np.std(heading_rad(m.S)) < 1.3 * before


def test_lone_measurement_births_with_the_paper_existence():
    # eq. 15 and IV-E: r = (xi - 1) / xi with xi = 1 + mu_N / mu_0 * 0.5 sum_c f(pi | c)
    cfg = SpaMapperConfig(mode="clairvoyant", n_particles=50)
    m = SpaMapper(cfg, [0.0, 0.0, 1.5, 0.0, 0.0], np.random.default_rng(0))
    m.tile_update([[-20.0, 50.0]], [0.7])
    f = 0.5 * (beta_pdf(0.7, *cfg.class_beta_1) + beta_pdf(0.7, *cfg.class_beta_2))
    a = cfg.new_object_mean / cfg.clutter_mean * f
    assert m.r == pytest.approx([a / (1.0 + a)], rel=1e-9)


@pytest.mark.parametrize("mode", ["spa", "ins_filter", "ins_plain"])
def test_batched_nav_updates_equal_one_at_a_time(mode):
    # the survey hands the mapper every INS output between two tiles at once: the same filter
    # (draws, weights, resampling) as one call per output, including a repeated time (dt = 0)
    t = np.array([1.0, 2.0, 3.0, 3.0, 4.0, 5.5, 6.0, 7.0, 8.0, 9.0])
    g = np.column_stack([1.5 * t + 0.3 * np.sin(t), 0.2 * t, 0.05 * np.cos(t)])
    cfg = SpaMapperConfig(mode=mode, n_particles=200)
    one = SpaMapper(cfg, [0.0, 0.0, 1.5, 0.0, 0.0], np.random.default_rng(7))
    batch = SpaMapper(cfg, [0.0, 0.0, 1.5, 0.0, 0.0], np.random.default_rng(7))
    for tk, gk in zip(t, g):
        one.nav_update(float(tk), gk)
    batch.nav_updates(t[:4], g[:4])
    batch.nav_updates(t[4:], g[4:])
    assert np.array_equal(one.S, batch.S) and np.array_equal(one.w, batch.w)
    assert np.allclose(one.vehicle_estimate(), batch.vehicle_estimate(), rtol=1e-12, atol=1e-12)
    if mode != "ins_plain":
        assert np.ptp(one.w) > 0.0 or len(np.unique(one.S[:, 0])) < cfg.n_particles  # weighted or resampled
    with pytest.raises(ValueError):
        batch.nav_updates(t[:3], g[:2])
