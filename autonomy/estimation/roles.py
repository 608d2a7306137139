"""The estimation roles as interfaces: what a component must offer to stand in a role, so that
estimators are composed from parts and a part is swapped for another of the same role
(the split of the Stone Soup tracking framework, [StoneSoup]).

===================  =========================================  ==========================================
role                 what it offers                             shipped parts
===================  =========================================  ==========================================
transition model     ``matrix(dt)``, ``covar(dt)``,             :class:`~autonomy.estimation.transition.ConstantPosition`,
                     ``function(x, dt)``, ``ndim_state``        :class:`~autonomy.estimation.transition.ConstantVelocity`
measurement model    ``function(x)``, ``jacobian(x)``,          :class:`~autonomy.estimation.measurement.PositionFix`,
                     ``residual(z, z_pred)``                    :class:`~autonomy.estimation.measurement.RangeBearingElevation`,
                                                                :class:`~autonomy.estimation.measurement.RangeAzimuth`
predictor            ``predict(mean, covar, dt_s)``             :class:`~autonomy.estimation.predictor.KalmanPredictor`
updater              ``update(mean, covar, z, noise_covar)``    :class:`~autonomy.estimation.updater.KalmanUpdater`,
                                                                :class:`~autonomy.estimation.updater.ConsiderKalmanUpdater`,
                                                                :class:`~autonomy.estimation.updater.ExtendedKalmanUpdater`
gater                ``rejects(maha2)``                         :class:`~autonomy.estimation.gater.MahalanobisGater`
initiator            ``initiate(z, noise_covar)``               :class:`~autonomy.estimation.initiator.SingleMeasurementInitiator`
deleter              ``deletes(t_s, t_last_update_s, n)``       :class:`~autonomy.estimation.deleter.UpdateTimeDeleter`
reprocessor          ``append(e)``, ``insert(e, t_s)``,         :class:`~autonomy.estimation.reprocessing.ReprocessingHistory`
                     ``prune(before_s)``
===================  =========================================  ==========================================

Means are (n,) arrays and covariances (n, n), in the estimator's state units and frame; a
state with its time is a :class:`~autonomy.estimation.state.GaussianState`. The one Kalman
update of a linearised measurement is :func:`~autonomy.estimation.updater.kalman_update`,
which the navigation filters and the tracker call with their own Jacobians.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

from numpy.typing import ArrayLike, NDArray


@runtime_checkable
class TransitionModel(Protocol):
    ndim_state: int

    def matrix(self, dt_s: float) -> NDArray: ...

    def covar(self, dt_s: float) -> NDArray: ...

    def function(self, state: ArrayLike, dt_s: float) -> NDArray: ...


@runtime_checkable
class MeasurementModel(Protocol):
    def function(self, state: ArrayLike) -> NDArray: ...

    def jacobian(self, state: ArrayLike) -> NDArray: ...

    def residual(self, z: ArrayLike, z_pred: ArrayLike) -> NDArray: ...


@runtime_checkable
class Predictor(Protocol):
    def predict(self, mean: ArrayLike, covar: ArrayLike, dt_s: float) -> tuple[NDArray, NDArray]: ...


@runtime_checkable
class Updater(Protocol):
    def update(self, mean: ArrayLike, covar: ArrayLike, z: ArrayLike, noise_covar: ArrayLike
               ) -> tuple[NDArray, NDArray]: ...


@runtime_checkable
class Gater(Protocol):
    def rejects(self, maha2: ArrayLike) -> NDArray: ...


@runtime_checkable
class Initiator(Protocol):
    def initiate(self, z: ArrayLike, noise_covar: ArrayLike) -> tuple[NDArray, NDArray]: ...


@runtime_checkable
class Deleter(Protocol):
    def deletes(self, t_s: float, t_last_update_s: float, n_updates: int) -> bool: ...


@runtime_checkable
class Reprocessor(Protocol):
    def append(self, event: Any) -> Any: ...

    def insert(self, event: Any, t_s: float) -> Any: ...

    def prune(self, before_s: float, *, inclusive: bool = False) -> None: ...
