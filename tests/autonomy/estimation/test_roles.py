"""Every shipped estimation part stands in its role (the interfaces of autonomy.estimation.roles),
a part missing a role's method does not, and the Gaussian state keeps its arrays unchanged."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.estimation import roles
from autonomy.estimation.deleter import UpdateTimeDeleter
from autonomy.estimation.gater import MahalanobisGater
from autonomy.estimation.initiator import SingleMeasurementInitiator
from autonomy.estimation.measurement import PositionFix, RangeAzimuth, RangeBearingElevation
from autonomy.estimation.predictor import KalmanPredictor
from autonomy.estimation.reprocessing import ReprocessingHistory
from autonomy.estimation.state import GaussianState
from autonomy.estimation.transition import ConstantPosition, ConstantVelocity
from autonomy.estimation.updater import ConsiderKalmanUpdater, ExtendedKalmanUpdater, KalmanUpdater

FIX = PositionFix(6, (0, 1, 2), np.eye(3))
PARTS = [
    (roles.TransitionModel, ConstantPosition(0.1)), (roles.TransitionModel, ConstantVelocity(0.1)),
    (roles.MeasurementModel, FIX), (roles.MeasurementModel, RangeBearingElevation()),
    (roles.MeasurementModel, RangeAzimuth()),
    (roles.Predictor, KalmanPredictor(ConstantVelocity(0.1))),
    (roles.Updater, KalmanUpdater(FIX)), (roles.Updater, ConsiderKalmanUpdater(FIX)),
    (roles.Updater, ExtendedKalmanUpdater(RangeBearingElevation())),
    (roles.Gater, MahalanobisGater(9.0)), (roles.Initiator, SingleMeasurementInitiator(FIX)),
    (roles.Deleter, UpdateTimeDeleter(10.0)),
    (roles.Reprocessor, ReprocessingHistory(lambda e: None, lambda: None, lambda s: None, lambda: 0.0)),
]


@pytest.mark.parametrize("role, part", PARTS, ids=[f"{r.__name__}-{type(p).__name__}" for r, p in PARTS])
def test_each_shipped_part_stands_in_its_role(role, part):
    assert isinstance(part, role)


def test_a_part_without_the_roles_method_does_not_stand_in_it():
    class HalfUpdater:
        def predict(self, mean, covar, dt_s):
            return mean, covar

    assert not isinstance(HalfUpdater(), roles.Updater)
    assert isinstance(HalfUpdater(), roles.Predictor)
    assert not isinstance(MahalanobisGater(9.0), roles.Updater)


def test_a_gaussian_state_is_read_only_and_checked():
    mean, covar = np.zeros(3), np.eye(3)
    s = GaussianState(mean, covar, 2.5)
    assert s.ndim == 3 and s.t_s == 2.5
    with pytest.raises(ValueError):
        s.mean[0] = 1.0  # a stored state never changes
    mean[0] = 7.0  # the caller's own array stays writable; of() copies
    assert GaussianState.of(mean, covar).mean[0] == 7.0 and mean.flags.writeable
    with pytest.raises(ValueError, match=r"mean must be \(n,\) and covar \(n, n\)"):
        GaussianState(np.zeros(3), np.eye(2))
    with pytest.raises(ValueError, match="mean must be"):
        GaussianState(np.zeros((3, 1)), np.eye(3))
