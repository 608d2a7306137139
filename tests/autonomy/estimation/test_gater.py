"""Chi-square gate thresholds against scipy.stats (the oracle the gate no longer imports)."""

import subprocess
import sys

import pytest
from scipy.stats import chi2

from autonomy.estimation.gater import MahalanobisGater


@pytest.mark.parametrize("dof", [1, 2, 3, 4, 6])
@pytest.mark.parametrize("probability", [1e-3, 0.5, 0.9, 0.95, 0.99, 0.999, 0.9999])
def test_chi_square_gate_is_scipy_stats_quantile_bit_for_bit(dof, probability):
    assert MahalanobisGater.chi_square(probability, dof).threshold == float(chi2.ppf(probability, dof))


def test_survey_mission_builds_without_scipy_stats():
    """The survey mission (PMHA gates, no target tracking) does not load scipy.stats."""
    code = ("import sys; from scenarios import load_scenario; from sim.mission import Mission; "
            "Mission(load_scenario('cssn_lawnmower')).reset(); print('scipy.stats' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=300)
    assert out.stdout.strip().splitlines()[-1] == "False"


def test_one_innovation_gate_matches_the_batch_and_the_chi_square_quantile():
    """The single-pair distance the navigation filter, the late-fix wrapper and the tracker
    gate with equals the batch one of the world model, and ``admits`` is its complement."""
    import numpy as np
    from scipy.stats import chi2

    from autonomy.estimation.gater import MahalanobisGater, innovation_log_likelihoods, mahalanobis2

    rng = np.random.default_rng(5)
    for m in (1, 2, 3):
        A = rng.standard_normal((m, m))
        S = A @ A.T + 0.1 * np.eye(m)
        r = rng.standard_normal(m)
        batch, _ = innovation_log_likelihoods(np.zeros((1, m)), S[None], r[None], np.zeros((1, m, m)))
        assert mahalanobis2(r, S) == pytest.approx(float(batch[0, 0]), rel=1e-12)
        assert mahalanobis2(r, S) == pytest.approx(float(r @ np.linalg.inv(S) @ r), rel=1e-10)
        gate = MahalanobisGater.chi_square(0.99, m)
        assert gate.threshold == float(chi2.ppf(0.99, m))
        scaled = r * np.sqrt(gate.threshold / mahalanobis2(r, S))
        assert gate.admits(0.999 * scaled, S) and not gate.admits(1.001 * scaled, S)
