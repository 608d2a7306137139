"""Onboard MSIS features against independent oracles: scikit-image's CircleModel, scipy's
Student t, closed-form fuzzy-set areas and synthetic pools and tanks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.msis.circle_fit import circle_residuals, fit_circle_algebraic, mlesac_circle, mlesac_iterations
from autonomy.msis.fuzzy_segments import FuzzySegment, matching_degree
from autonomy.msis.line_segments import fit_line, iepf_split, t_quantile
from autonomy.msis.localization import fuse_wall_segments


def _circle_points(rng, centre, radius, n, sigma, arc=(0.0, 2 * np.pi)):
    a = rng.uniform(*arc, n)
    r = radius + rng.normal(0.0, sigma, n)
    return np.column_stack([centre[0] + r * np.cos(a), centre[1] + r * np.sin(a)])


def test_algebraic_fit_agrees_with_scikit_image_circle_model():
    skm = pytest.importorskip("skimage.measure")
    rng = np.random.default_rng(1)
    for trial in range(20):
        pts = _circle_points(rng, rng.uniform(-50, 50, 2), rng.uniform(2, 20), 40, 0.05, arc=(0.0, rng.uniform(1, 6)))
        c, r = fit_circle_algebraic(pts)
        if hasattr(skm.CircleModel, "from_estimate"):
            model = skm.CircleModel.from_estimate(pts)
        else:  # scikit-image < 0.26
            model = skm.CircleModel()
            assert model.estimate(pts)
        assert np.allclose(c, model.center, atol=1e-6) and abs(r - model.radius) < 1e-6


def test_algebraic_fit_rejects_collinear_points():
    with pytest.raises(ValueError, match="collinear"):
        fit_circle_algebraic([[0, 0], [1, 1], [2, 2], [3, 3]])


def test_iteration_count_is_algorithm_1_line_2():
    assert mlesac_iterations(0.01, 0.5) == math.ceil(math.log(0.01) / math.log(1 - 0.125)) == 35


def test_mlesac_recovers_the_circle_with_half_uniform_outliers_in_99_of_100_trials():
    centre, radius = np.array([2.0, -1.0]), 6.0
    ok = 0
    for seed in range(100):
        rng = np.random.default_rng(seed)
        inl = _circle_points(rng, centre, radius, 100, 0.03)
        out = rng.uniform(-8, 8, (100, 2)) + centre
        pts = rng.permutation(np.vstack([inl, out]))
        fit = mlesac_circle(pts, 0.1, 1e-3, 0.5, rng)
        if fit is not None and np.linalg.norm(fit.centre - centre) < 0.05 and abs(fit.radius_m - radius) < 0.05:
            ok += 1
            # the refit is the algebraic fit of exactly the inliers it reports
            c2, r2 = fit_circle_algebraic(pts[fit.inliers])
            assert np.allclose(c2, fit.centre) and r2 == pytest.approx(fit.radius_m)
            assert np.all(circle_residuals(pts[fit.inliers], fit.centre, fit.radius_m) < 0.2)
    assert ok >= 99


@pytest.mark.parametrize("dof", [1, 2, 5, 17, 120])
@pytest.mark.parametrize("p", [0.025, 0.16, 0.5, 0.84, 0.975, 0.999])
def test_t_quantile_matches_scipy(dof, p):
    stats = pytest.importorskip("scipy.stats")
    assert t_quantile(p, dof) == pytest.approx(stats.t.ppf(p, dof), rel=1e-9, abs=1e-12)


def _rectangle_scan(rng, half_n, half_e, viewpoint, n, sigma):
    """Points where rays from ``viewpoint`` hit the inside of an axis-aligned rectangle, in
    angle order (as one sonar turn), with range noise."""
    ang = np.linspace(-np.pi, np.pi, n, endpoint=False)
    d = np.column_stack([np.cos(ang), np.sin(ang)])
    with np.errstate(divide="ignore"):
        tn = np.where(d[:, 0] != 0, (np.sign(d[:, 0]) * half_n - viewpoint[0]) / d[:, 0], np.inf)
        te = np.where(d[:, 1] != 0, (np.sign(d[:, 1]) * half_e - viewpoint[1]) / d[:, 1], np.inf)
    t = np.minimum(tn, te) + rng.normal(0, sigma, n)
    return viewpoint + t[:, None] * d


def test_iepf_and_eigenvector_fit_recover_every_wall_of_a_rectangle():
    rng = np.random.default_rng(3)
    pts = _rectangle_scan(rng, 10.0, 5.0, np.array([2.0, -1.0]), 400, 0.02)
    runs = iepf_split(pts, k_min=8, rho_max_m=0.15)
    fits = [fit_line(pts[a:b]) for a, b in runs]
    walls = {(0.0, 10.0), (np.pi, 10.0), (np.pi / 2, 5.0), (-np.pi / 2, 5.0)}  # (theta, rho) of x cos + y sin = rho
    for theta, rho in walls:
        best = min(fits, key=lambda f: abs(math.remainder(f.theta_rad - theta, 2 * np.pi)) + abs(f.rho_m - rho))
        assert abs(math.degrees(math.remainder(best.theta_rad - theta, 2 * np.pi))) <= 1.0
        assert best.rho_m == pytest.approx(rho, abs=0.05)
    # the interval uses Student's t with k - 1 dof
    stats = pytest.importorskip("scipy.stats")
    f = fits[0]
    assert f.rho_interval(0.95) == pytest.approx(stats.t.ppf(0.975, f.n_points - 1) * f.sigma_rho_m)


def test_line_fit_sigma_rho_matches_monte_carlo():
    rng = np.random.default_rng(5)
    x = np.linspace(-2, 2, 30)
    rhos, sigmas = [], []
    for _ in range(2000):
        pts = np.column_stack([x, 3.0 + rng.normal(0, 0.05, 30)])
        f = fit_line(pts)
        rhos.append(f.rho_m)
        sigmas.append(f.sigma_rho_m)
    assert np.std(rhos) == pytest.approx(np.mean(sigmas), rel=0.1)


def test_matching_degree_closed_forms():
    # two rectangles (rho0 = rho1) of half width 1 offset by 1: overlap 1 over the smaller area 2
    assert matching_degree(0.0, 1.0, 1.0, 1.0, 1.0, 1.0) == pytest.approx(0.5, abs=2e-3)
    assert matching_degree(0.0, 0.2, 0.5, 0.0, 0.2, 0.5) == pytest.approx(1.0, abs=1e-3)
    assert matching_degree(0.0, 0.2, 0.5, 2.0, 0.2, 0.5) == 0.0
    # two triangles (rho1 = 0) of half width 1 centred 1 apart: intersection is a triangle of area 1/4
    assert matching_degree(0.0, 0.0, 1.0, 1.0, 0.0, 1.0) == pytest.approx(0.25, abs=2e-3)


def test_fuzzy_segments_fuse_grow_and_age_out():
    a = FuzzySegment(0.0, 5.0, 0.01, 0.02, 0.04, np.array([5.0, -2.0]), np.array([5.0, 1.0]), 0.0)
    b = FuzzySegment(0.002, 5.01, 0.01, 0.02, 0.04, np.array([5.01, 0.5]), np.array([5.01, 3.0]), 1.0)
    far = FuzzySegment(0.0, 7.0, 0.01, 0.02, 0.04, np.array([7.0, 0.0]), np.array([7.0, 1.0]), 1.0)
    assert a.matches(b, math.radians(2), 0.3) and not a.matches(far, math.radians(2), 0.3)
    f = a.fused(b)
    assert f.rho_m == pytest.approx(5.005, abs=2e-3) and f.rho0_m == pytest.approx(0.04 / math.sqrt(2))
    assert f.end_a[1] == pytest.approx(-2.0, abs=0.02) and f.end_b[1] == pytest.approx(3.0, abs=0.02)


def _split_wall_pieces(rng):
    """A wall ``x = 5`` seen as four IEPF pieces of one sweep: three long, one short and noisy
    (its own fit is off by degrees)."""
    pieces = []
    for (y0, y1, k, sigma) in [(-4.0, -1.5, 40, 0.02), (-1.4, 0.4, 30, 0.02), (0.5, 1.3, 8, 0.06), (1.4, 4.0, 40, 0.02)]:
        y = np.linspace(y0, y1, k)
        pieces.append(fit_line(np.column_stack([5.0 + rng.normal(0, sigma, k), y])))
    return [FuzzySegment.from_fit(f, 0.0) for f in pieces]


def test_a_wall_split_into_pieces_fuses_into_one_segment_within_1_deg():
    worst, fused_err = [], []
    for seed in range(50):
        segs = _split_wall_pieces(np.random.default_rng(seed))
        f = fuse_wall_segments(segs, np.array([1.0, 0.0]))
        fused_err.append(abs(math.degrees(math.remainder(f.theta_rad, 2 * np.pi))))
        worst.append(max(abs(math.degrees(math.remainder(s.theta_rad, 2 * np.pi))) for s in segs))
        assert f.rho_m == pytest.approx(5.0, abs=0.02)
        assert min(f.end_a[1], f.end_b[1]) < -3.9 and max(f.end_a[1], f.end_b[1]) > 3.9  # spans the wall
        assert f.sigma_theta_rad < min(s.sigma_theta_rad for s in segs)
    assert max(fused_err) <= 1.0
    assert max(worst) > 2.0  # the short piece alone would not meet the goal


def test_fusion_turns_pieces_to_the_wall_normal_side():
    a = FuzzySegment(0.0, 5.0, 0.01, 0.02, 0.04, np.array([5.0, -2.0]), np.array([5.0, 0.0]), 0.0)
    b = FuzzySegment(math.pi, -5.0, 0.01, 0.02, 0.04, np.array([5.0, 0.0]), np.array([5.0, 2.0]), 0.0)
    f = fuse_wall_segments([a, b], np.array([1.0, 0.0]))
    assert f.theta_rad == pytest.approx(0.0, abs=1e-9) and f.rho_m == pytest.approx(5.0)


def test_heading_uncertainty_widens_rho_cuts_with_the_lever_arm_and_adds_to_the_angle():
    s = FuzzySegment(0.0, 5.0, 0.01, 0.02, 0.04, np.array([5.0, -1.0]), np.array([5.0, 4.0]), 0.0)
    sp = math.radians(1.0)
    h = s.with_heading_uncertainty(np.array([0.0, 1.0]), sp)
    assert h.rho1_m == pytest.approx(0.02 + 3.0 * sp) and h.rho0_m == pytest.approx(0.04 + 1.96 * 3.0 * sp)
    assert h.sigma_theta_total_rad == pytest.approx(math.hypot(0.01, sp)) and h.sigma_theta_rad == 0.01


def test_wall_fix_is_unaffected_by_a_heading_error_rotating_the_sweep():
    from autonomy.messages import NavEstimate
    from autonomy.msis.config import MsisLocalizationConfig
    from autonomy.msis.localization import MsisLocalizer

    rng = np.random.default_rng(11)
    true_p = np.array([3.0, -1.5])
    pts = _rectangle_scan(rng, 10.0, 5.0, true_p, 600, 0.02)
    psi = math.radians(1.5)  # heading error: the sweep is placed rotated about the estimate
    est_p = true_p + np.array([0.4, -0.3])
    R = np.array([[math.cos(psi), -math.sin(psi)], [math.sin(psi), math.cos(psi)]])
    placed = est_p + (pts - true_p) @ R.T
    loc = MsisLocalizer(MsisLocalizationConfig(method="walls", tank_size_ne_m=(20.0, 10.0)), rng)
    nav = NavEstimate(0.0, np.array([*est_p, 2.0]), np.zeros(3), np.zeros(3), np.zeros(3), np.eye(3))
    pos, cov, (heading_err, heading_var) = loc._walls_fix(placed, nav)
    assert np.linalg.norm(pos - true_p) < 0.05
    # the walls' known directions give the heading error the sweep was placed with
    assert math.degrees(heading_err) == pytest.approx(1.5, abs=0.2) and 0 < heading_var < math.radians(0.5) ** 2
    assert sorted(loc.last_walls) == [0, 1, 2, 3]
    for i, s in loc.last_walls.items():  # one fused estimate per wall, turned by the heading error
        assert abs(abs(math.degrees(math.remainder(s.theta_rad - [0, np.pi, np.pi / 2, -np.pi / 2][i], 2 * np.pi))) - 1.5) < 0.5
