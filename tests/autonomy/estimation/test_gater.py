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
