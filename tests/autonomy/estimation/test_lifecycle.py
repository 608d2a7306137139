"""Initiator and deleter: states started from one measurement, tentative states forgotten."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.estimation.deleter import UpdateTimeDeleter
from autonomy.estimation.initiator import SingleMeasurementInitiator
from autonomy.estimation.measurement import PositionFix, RangeBearingElevation


def test_position_fix_initiation_copies_the_fix_and_keeps_the_prior_elsewhere():
    R = np.array([[0.2, 0.05, 0.0], [0.05, 0.3, 0.0], [0.0, 0.0, 0.1]])
    mean, covar = SingleMeasurementInitiator(PositionFix(3, (0, 1, 2))).initiate([1.0, 2.0, 3.0], R)
    np.testing.assert_array_equal(mean, [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(covar, R)
    prior_cov = np.diag([9.0, 9.0, 4.0, 4.0])
    init = SingleMeasurementInitiator(PositionFix(4, (0, 1)), prior_mean=np.zeros(4), prior_covar=prior_cov)
    mean, covar = init.initiate([5.0, -1.0], 0.5 * np.eye(2))
    np.testing.assert_array_equal(mean, [5.0, -1.0, 0.0, 0.0])  # velocity from the prior
    np.testing.assert_array_equal(covar, np.diag([0.5, 0.5, 4.0, 4.0]))


def test_spherical_initiation_matches_monte_carlo_propagation():
    model = RangeBearingElevation(mount_pos_m=(0.3, 0.0, 0.2))
    z = np.array([40.0, 0.6, 0.3])
    R = np.diag([0.05**2, 0.002**2, 0.002**2])
    mean, covar = SingleMeasurementInitiator(model).initiate(z, R)
    rng = np.random.default_rng(0)
    samples = np.array([model.inverse(s) for s in rng.multivariate_normal(z, R, size=20000)])
    np.testing.assert_allclose(mean, model.inverse(z))
    np.testing.assert_allclose(samples.mean(axis=0), mean, atol=4e-3)
    np.testing.assert_allclose(np.cov(samples.T), covar, rtol=0.05, atol=1e-5)


@pytest.mark.parametrize("t_s,n,deleted", [(10.0, 1, False), (10.1, 1, True), (10.1, 2, False), (50.0, 3, False)])
def test_update_time_deleter_forgets_only_stale_tentative_states(t_s, n, deleted):
    assert UpdateTimeDeleter(max_age_s=5.0, min_updates=2).deletes(t_s, 5.0, n) is deleted


def test_update_time_deleter_without_confirmation_forgets_any_stale_state():
    d = UpdateTimeDeleter(max_age_s=5.0)
    assert d.deletes(10.1, 5.0, 100) and not d.deletes(9.9, 5.0, 100)
    with pytest.raises(ValueError):
        UpdateTimeDeleter(max_age_s=0.0)
