"""SPA mapper: motion model, association weights against closed forms, and small surveys."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.mapping.auv_motion import nct_predict
from autonomy.mapping.config import SpaMapperConfig
from autonomy.mapping.spa_mapper import SpaMapper, beta_pdf
from sim.mcm.survey import LawnmowerPath, McmSurveyConfig, run_survey


def test_nct_closes_a_circle_and_matches_constant_velocity():
    s0 = np.array([[10.0, -5.0, 1.5, 0.0, 2 * np.pi / 100.0]])
    s = s0.copy()
    for _ in range(100):
        s = nct_predict(s, 1.0, 0.0, 0.0, np.random.default_rng(0))
    assert s[0, :4] == pytest.approx(s0[0, :4], abs=1e-9)
    cv = nct_predict(np.array([[0.0, 0.0, 1.0, 2.0, 0.0]]), 3.0, 0.0, 0.0, np.random.default_rng(0))
    assert cv[0] == pytest.approx([3.0, 6.0, 1.0, 2.0, 0.0])


def test_beta_pdf_matches_scipy():
    from scipy.stats import beta

    x = np.linspace(0.05, 0.95, 7)
    assert beta_pdf(x, 6.0, 2.0) == pytest.approx(beta.pdf(x, 6.0, 2.0))


def test_association_weight_is_the_gaussian_convolution():
    # one PO with Gaussian particles, a known vehicle state: beta_k(m) = r pd ratio N(ell; mu, P + s^2 I) f(pi|c)
    cfg = SpaMapperConfig(mode="clairvoyant", n_particles=20000)
    rng = np.random.default_rng(5)
    m = SpaMapper(cfg, [0.0, 0.0, 1.5, 0.0, 0.0], rng)
    mu_ned, sd = np.array([-25.0, 60.0]), 2.0  # 25 m behind, 60 m to starboard (heading north)
    m.r = np.array([0.6])
    m.X = (mu_ned + sd * rng.standard_normal((cfg.n_particles, 2)))[None]
    m.W = np.zeros((1, cfg.n_particles, 2))
    m.W[0, :, 0] = 1.0 / cfg.n_particles  # class 1 surely
    ell = np.array([[-24.0, 61.5], [-10.0, 30.0]])
    f_pi = np.array([[3.0, 0.5], [1.0, 1.0]])
    veh = np.repeat(np.array([[0.0, 0.0, 1.5, 0.0, 0.0]]), cfg.n_particles, axis=0)
    beta = m.association_weights(np.array([0]), veh, ell, f_pi)
    var = sd ** 2 + cfg.sigma_meas_m ** 2
    local_mu = np.array([-25.0, 60.0])
    ratio = m.tile_area_m2 / cfg.clutter_mean
    for j in range(2):
        g = np.exp(-0.5 * np.sum((ell[j] - local_mu) ** 2) / var) / (2 * np.pi * var)
        assert beta[0, j + 1] == pytest.approx(0.6 * cfg.pd * ratio * g * f_pi[j, 0], rel=0.05)
    assert beta[0, 0] == pytest.approx(0.4 + 0.6 * (1 - cfg.pd), rel=1e-3)  # all particles in the tile


def test_lawnmower_path_is_continuous_at_constant_speed():
    cfg = McmSurveyConfig(n_lanes=3)
    path = LawnmowerPath(cfg)
    t = np.arange(0.0, path.duration_s, 0.5)
    st = path.state(t)
    step = np.linalg.norm(np.diff(st[:, :2], axis=0), axis=1)
    assert np.all(step <= 0.75 + 1e-9) and np.all(step >= 0.75 * np.cos(0.5 * 0.5 * 1.5 / 10.0) - 1e-6)
    assert path.duration_s * cfg.speed_mps == pytest.approx(cfg.survey_length_m)


def test_clairvoyant_and_spa_map_a_small_survey():
    cfg = McmSurveyConfig(n_lanes=4, n_other=6, n_particles=200, clutter_mean=0.0,
                          modes=("clairvoyant", "spa"), seed=3)
    r = run_survey(cfg, 0)
    n_true = 5 + 6
    for mode in ("clairvoyant", "spa"):
        # the four lanes see every object inside 20..130 m abeam of some lane
        assert r[mode]["class_accuracy"] == 1.0
        assert r[mode]["final_gospa"] < 0.5 * 50 * n_true  # most objects mapped, few false
    assert r["clairvoyant"]["auv_rmse_m"] == 0.0
    assert r["spa"]["auv_rmse_m"] < 5.0


def test_bad_config_is_refused():
    with pytest.raises(ValueError, match="longer than the survey"):
        McmSurveyConfig(n_lanes=1, area_side_m=40.0, tile_length_m=50.0)
    with pytest.raises(ValueError):
        McmSurveyConfig(pd=-0.1)


def test_association_weight_under_a_wide_vehicle_belief_is_the_gaussian_convolution():
    # vehicle drawn from N(0, diag(20^2, 8^2)) m with heading N(0, 1 deg^2), PO from N(mu, 0.7^2 I):
    # beta = r pd ratio f N(ell; mu_local, diag(20^2, 8^2) + 0.7^2 + 1^2 + heading term), closed form
    # (randomly paired particles gave 0 or several times this at 300 pairs)
    cfg = SpaMapperConfig(mode="spa", n_particles=400)
    rng = np.random.default_rng(11)
    m = SpaMapper(cfg, [0.0, 0.0, 1.5, 0.0, 0.0], rng)
    n = cfg.n_particles
    psi = np.deg2rad(1.0) * rng.standard_normal(n)
    veh = np.column_stack([20.0 * rng.standard_normal(n), 8.0 * rng.standard_normal(n), 1.5 * np.cos(psi),
                           1.5 * np.sin(psi), np.zeros(n)])
    mu = np.array([-25.0, 60.0])  # heading north: along = north, across = east
    m.r = np.array([0.7])
    m.X = (mu + 0.7 * rng.standard_normal((n, 2)))[None]
    m.W = np.full((1, n, 2), 0.5 / n)
    ell = np.array([[-21.0, 61.0], [-32.0, 58.0]])
    f_pi = np.array([[2.0, 0.5], [1.0, 1.0]])
    beta = m.association_weights(np.array([0]), veh, ell, f_pi)
    var_psi = np.deg2rad(1.0) ** 2
    J = np.array([mu[1], -mu[0]])  # d(local) / d(heading) at the PO
    S = np.diag([400.0 + 0.49 + 1.0, 64.0 + 0.49 + 1.0]) + var_psi * np.outer(J, J)
    ratio = m.tile_area_m2 / cfg.clutter_mean
    for j in range(2):
        e = ell[j] - mu
        g = np.exp(-0.5 * e @ np.linalg.solve(S, e)) / (2 * np.pi * np.sqrt(np.linalg.det(S)))
        assert beta[0, j + 1] == pytest.approx(0.7 * cfg.pd * ratio * g * f_pi[j].mean(), rel=0.1)


def test_detection_probability_is_blurred_across_a_tile_edge():
    # a PO on the along-track edge of the tile with a vehicle belief of several metres along
    # track: E_s[P_d] = pd / 2 (a hard edge at the mean state would give 0 or pd)
    cfg = SpaMapperConfig(mode="spa", n_particles=2000)
    m = SpaMapper(cfg, [0.0, 0.0, 1.5, 0.0, 0.0], np.random.default_rng(2))
    L = np.array([[0.0, 60.0], [-50.0, -60.0], [-25.0, 75.0], [-25.0, 20.0]])
    p = m._in_tile_probability(L, np.full(4, 4.0), np.full(4, 1e-6))
    assert p == pytest.approx([0.5, 0.5, 1.0, 0.5], abs=1e-6)


def test_coincident_pos_merge_and_distinct_ones_stay():
    cfg = SpaMapperConfig(mode="clairvoyant", n_particles=200)
    rng = np.random.default_rng(8)
    m = SpaMapper(cfg, [0.0, 0.0, 1.5, 0.0, 0.0], rng)
    centres = np.array([[100.0, 50.0], [100.8, 50.5], [100.0, 58.0], [300.0, 300.0]])
    m.r = np.array([0.9, 0.95, 0.9, 0.01])
    m.X = centres[:, None, :] + 0.5 * rng.standard_normal((4, cfg.n_particles, 2))
    m.W = np.full((4, cfg.n_particles, 2), 0.5 / cfg.n_particles)
    m._merge_coincident()
    # 0.9 m apart with 0.5 m spreads: one PO (the likelier one's belief); 8 m away: another object
    assert len(m.r) == 3
    assert m.r[0] == pytest.approx(1.0 - 0.1 * 0.05)
    assert m.X[0].mean(0) == pytest.approx(centres[1], abs=0.1)
    assert m.X[1].mean(0) == pytest.approx(centres[2], abs=0.1) and m.r[2] == 0.01


def test_hand_worked_one_object_update_heading_east():
    # vehicle at the origin heading east (NED yaw 90 deg): a detection 25 m behind and 60 m to
    # starboard is the object at north -60, east -25. A PO there (r 0.5, zero spread, classes
    # 50/50) and one detection: BP gives nu = 1 / xi, the PO factor is
    # z = (1 - pd) + pd / (mu_0 f_FA) nu N(0; 0, s^2 I) mean_c f(pi | c), r' = r z / (r z + 1 - r)
    cfg = SpaMapperConfig(mode="clairvoyant", n_particles=50, merge_gate=0.0)
    m = SpaMapper(cfg, [0.0, 0.0, 0.0, 1.5, 0.0], np.random.default_rng(0))
    m.set_true_state([0.0, 0.0, 0.0, 1.5, 0.0])
    m.r = np.array([0.5])
    m.X = np.tile([-60.0, -25.0], (1, cfg.n_particles, 1))
    m.W = np.full((1, cfg.n_particles, 2), 0.5 / cfg.n_particles)
    pi1 = 0.7
    f = 0.5 * (beta_pdf(pi1, *cfg.class_beta_1) + beta_pdf(pi1, *cfg.class_beta_2))
    xi = 1.0 + cfg.new_object_mean / cfg.clutter_mean * f
    ratio = 2 * cfg.tile_length_m * cfg.tile_width_m / cfg.clutter_mean
    beta1 = 0.5 * cfg.pd * ratio * f / (2 * np.pi * cfg.sigma_meas_m ** 2)
    beta0 = 0.5 + 0.5 * (1.0 - cfg.pd)
    z = (1.0 - cfg.pd) + cfg.pd * ratio * (1.0 / xi) * f / (2 * np.pi * cfg.sigma_meas_m ** 2)
    m.tile_update([[-25.0, 60.0]], [pi1])
    assert m.last_association.p_object[0] == pytest.approx([beta0 / (beta0 + beta1 / xi),
                                                           beta1 / xi / (beta0 + beta1 / xi)])
    assert m.r[0] == pytest.approx(0.5 * z / (0.5 * z + 0.5), rel=1e-9)
    # the detection's new PO has existence (xi - 1) / (xi + phi) < P_th: pruned
    assert (xi - 1.0) / (xi + beta1 / beta0) < cfg.prune_threshold and len(m.r) == 1
    # without the legacy PO it is born at the object, existence (xi - 1) / xi
    fresh = SpaMapper(cfg, [0.0, 0.0, 0.0, 1.5, 0.0], np.random.default_rng(1))
    fresh.set_true_state([0.0, 0.0, 0.0, 1.5, 0.0])
    fresh.tile_update([[-25.0, 60.0]], [pi1])
    assert fresh.r == pytest.approx([(xi - 1.0) / xi]) and fresh.X[0].mean(0) == pytest.approx([-60.0, -25.0], abs=0.3)
    # class: the factor of class c is (1 - pd) + pd ratio nu N f(pi | c)
    w = m.W[0].sum(0)
    k = cfg.pd * ratio / xi / (2 * np.pi * cfg.sigma_meas_m ** 2)
    f1, f2 = beta_pdf(pi1, *cfg.class_beta_1), beta_pdf(pi1, *cfg.class_beta_2)
    assert w[0] / w[1] == pytest.approx((1 - cfg.pd + k * f1) / (1 - cfg.pd + k * f2), rel=1e-9)
