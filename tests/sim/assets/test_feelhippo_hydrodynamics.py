"""FeelHippo hydrodynamic estimates: re-derived from the envelope, and pitch-stable at speed.

The checks here read ``sim/assets/feelhippo/params.yaml`` as plain YAML and compute
independently of the simulator's code path:

* translational added mass = Lamb's ellipsoid coefficients (Lamb 1932, Hydrodynamics,
  sec. 114; Imlay 1961, DTMB report 1528; Fossen 2021, Handbook of Marine Craft
  Hydrodynamics and Motion Control, sec. 8.4.2) for the ellipsoid with the envelope's axis
  ratios, times the displaced water; the elliptic integrals evaluated here by quadrature;
* rotational added inertia and rotational quadratic damping by strip theory over the
  envelope's faces (Newman 1977, Marine Hydrodynamics, ch. 4 and 7);
* the static pitch stability at speed: the metacentric restoring W z_g - B z_b (N m/rad)
  must exceed the Munk coefficient (Z_wdot - X_udot) U^2 (Newman 1977, ch. 4), else a
  hull flying level at U is statically unstable in pitch.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.integrate import quad

PARAMS_YAML = Path(__file__).resolve().parents[3] / "sim" / "assets" / "feelhippo" / "params.yaml"
GRAVITY_MPS2 = 9.81


@pytest.fixture(scope="module")
def raw() -> dict:
    return yaml.safe_load(PARAMS_YAML.read_text())


def lamb_ellipsoid_integrals(semi_axes_m) -> tuple[float, float, float]:
    """(alpha_0, beta_0, gamma_0) of an ellipsoid with semi-axes (a, b, c) along x, y, z:
    alpha_0 = a b c int_0^inf dl / ((a^2 + l) Delta(l)), Delta = sqrt(prod(s_i^2 + l))."""
    a, b, c = semi_axes_m

    def delta(lam):
        return math.sqrt((a * a + lam) * (b * b + lam) * (c * c + lam))

    return tuple(a * b * c * quad(lambda lam, s=s: 1.0 / ((s * s + lam) * delta(lam)), 0.0, math.inf,
                                  epsabs=1e-12, epsrel=1e-10)[0] for s in (a, b, c))


def test_lamb_integrals_match_the_closed_forms():
    """Sphere: alpha_0 = 2/3, k = 1/2. Prolate spheroid a > b = c (Lamb 1932, sec. 114;
    Fossen 2021, sec. 8.4.2), e = sqrt(1 - (b/a)^2):
    alpha_0 = 2 (1 - e^2) / e^3 (atanh(e) - e), beta_0 = 1/e^2 - (1 - e^2) atanh(e) / e^3;
    L/D = 5 gives Lamb's tabulated k_1 = 0.059, k_2 = 0.894."""
    al, be, ga = lamb_ellipsoid_integrals((1.0, 1.0, 1.0))
    assert al == pytest.approx(2.0 / 3.0, rel=1e-8) and be == pytest.approx(ga, rel=1e-8)
    for a_over_b in (1.5, 5.0, 12.0):
        e = math.sqrt(1.0 - 1.0 / a_over_b ** 2)
        al, be, ga = lamb_ellipsoid_integrals((a_over_b, 1.0, 1.0))
        assert al == pytest.approx(2 * (1 - e * e) / e ** 3 * (math.atanh(e) - e), rel=1e-7)
        assert be == pytest.approx(1 / e ** 2 - (1 - e * e) * math.atanh(e) / e ** 3, rel=1e-7)
        assert ga == pytest.approx(be, rel=1e-8)
    al, be, _ = lamb_ellipsoid_integrals((5.0, 1.0, 1.0))
    assert al / (2 - al) == pytest.approx(0.059, abs=5e-4)
    assert be / (2 - be) == pytest.approx(0.894, abs=5e-4)


def test_added_mass_and_damping_follow_from_the_envelope(raw):
    """params.yaml holds the documented derivation (README.md), to its printed rounding."""
    rho = raw["rho_kgpm3"]
    L, B, H = raw["envelope_m"]
    displaced_kg = raw["mass_kg"] * raw["buoyancy_fraction"]  # rho V, V = B / (rho g)
    al, be, ga = lamb_ellipsoid_integrals((L / 2, B / 2, H / 2))
    assert al + be + ga == pytest.approx(2.0, rel=1e-8)
    k = np.array([al / (2 - al), be / (2 - be), ga / (2 - ga)])
    X_ud, Y_vd, Z_wd = k * displaced_kg
    K_pd = Z_wd * B ** 2 / 12 + Y_vd * H ** 2 / 12
    M_qd = Z_wd * L ** 2 / 12 + X_ud * H ** 2 / 12
    N_rd = Y_vd * L ** 2 / 12 + X_ud * B ** 2 / 12
    A = raw["added_mass"]
    np.testing.assert_allclose(A[:3], [X_ud, Y_vd, Z_wd], atol=0.051)
    np.testing.assert_allclose(A[3:], [K_pd, M_qd, N_rd], atol=0.0051)
    # Nearly cubic envelope: surge and heave added masses of similar size.
    assert 1.0 < A[2] / A[0] < 1.5

    # Rotational quadratic damping: strip theory over each face with the drag coefficient its
    # translational term implies, C_d,i = D_q,i / (0.5 rho A_i), A = (B H, L H, L B).
    Dq = raw["damping_quadratic"]
    cd_x, cd_y, cd_z = (Dq[i] / (0.5 * rho * area) for i, area in enumerate((B * H, L * H, L * B)))

    def face(cd, width_m, extent_m):  # int 0.5 rho cd width |s|^3 ds over the face
        return 0.5 * rho * cd * width_m * extent_m ** 4 / 32.0

    K_pp = face(cd_z, L, B) + face(cd_y, L, H)
    M_qq = face(cd_z, B, L) + face(cd_x, B, H)
    N_rr = face(cd_y, H, L) + face(cd_x, H, B)
    np.testing.assert_allclose(Dq[3:], [K_pp, M_qq, N_rr], atol=0.051)


def test_metacentric_restoring_exceeds_munk_moment_at_full_speed(raw):
    """Pitch stiffness at U = 1 m/s: W z_g - B z_b > (Z_wdot - X_udot) U^2, with margin."""
    W = raw["mass_kg"] * GRAVITY_MPS2
    B = W * raw["buoyancy_fraction"]
    restoring_nm_per_rad = W * raw["r_bg_m"][2] - B * raw["r_bb_m"][2]
    A = raw["added_mass"]
    u_mps = 1.0
    munk_nm_per_rad = (A[2] - A[0]) * u_mps ** 2
    assert restoring_nm_per_rad == pytest.approx(13.79, abs=0.01)
    assert munk_nm_per_rad < 0.5 * restoring_nm_per_rad
    # The estimate this replaces, [18, 28, 40, ...], failed it: 22 N m/rad > 13.8 N m/rad.
    assert (40.0 - 18.0) * u_mps ** 2 > restoring_nm_per_rad
