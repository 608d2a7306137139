"""INS drift (paper 003, eqs. 29-30): sample moments over 2000 draws against the equations."""

from __future__ import annotations

import numpy as np
import pytest

from sim.mcm.ins_drift import InsDriftParams, drift_mean, drift_variance, sample_drift


def test_eq29_eq30_closed_form_values():
    p = InsDriftParams()
    # 2 h, heading 0, lambda0 = 0: mean north 0.5 * 7.5 * 4 = 15 m, heading drift -2 deg (iota 1)
    m = drift_mean(7200.0, 0.0, 0.0, 1, p)
    assert m == pytest.approx([15.0, 0.0, -np.deg2rad(2.0)])
    v = drift_variance(7200.0, 0.0, 0.0, p)
    assert v == pytest.approx([7.5 ** 2 * 8 / 3, 0.0, np.deg2rad(0.6) ** 2 * 2])


def test_sample_moments_follow_eqs_29_30():
    rng = np.random.default_rng(11)
    t = np.arange(10.0, 10001.0, 10.0)  # over 2.8 h
    heading = np.where((t // 600) % 2 == 0, 0.3, 0.3 + np.pi)  # lawnmower legs
    lam, iota = 1.1, 0
    d, _, _ = sample_drift(t, heading, rng, lambda0_rad=lam, iota=iota, n_draws=2000)
    for k in (59, 300, 999):
        mean = drift_mean(t[k], heading[k], lam, iota)
        var = drift_variance(t[k], heading[k], lam)
        sm, sv = d[:, k].mean(axis=0), d[:, k].var(axis=0, ddof=1)
        # sample mean within 4 standard errors; sample variance within 4 of its standard errors
        assert np.all(np.abs(sm - mean) <= 4.0 * np.sqrt(var / 2000) + 1e-12)
        assert np.all(np.abs(sv - var) <= 4.0 * var * np.sqrt(2.0 / 1999) + 1e-12)


def test_draws_lambda_and_sign_and_rejects_bad_times():
    rng = np.random.default_rng(0)
    lams, iotas = zip(*[sample_drift([1.0, 2.0], [0.0, 0.0], rng)[1:] for _ in range(200)])
    assert 0.0 < min(lams) and max(lams) < 2 * np.pi and set(iotas) == {0, 1}
    with pytest.raises(ValueError):
        sample_drift([2.0, 1.0], [0.0, 0.0], rng)
    with pytest.raises(ValueError):
        InsDriftParams(eps_p_m_per_h2=-1.0)
