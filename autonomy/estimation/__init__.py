"""Estimation roles shared by the world model, trackers and mappers (their interfaces:
:mod:`autonomy.estimation.roles`; the state they pass: :class:`GaussianState`).

Transition models, measurement models, predictor, updater, gater, data associator,
same-scan clusterer, initiator, deleter and out-of-sequence re-processing, each a small swappable part checked alone against an oracle (the
split of the Stone Soup tracking framework, https://stonesoup.readthedocs.io).
"""

import lazy_loader

# names resolved on first use, so importing one submodule (a config, say) loads no other
__getattr__, __dir__, __all__ = lazy_loader.attach(__name__, submod_attrs={
    "assignment": ["murty_k_best", "ranked_associations"],
    "association": ["KBestAssociator"],
    "clustering": ["cluster_consistent", "fuse_cluster"],
    "deleter": ["UpdateTimeDeleter"],
    "gater": ["MahalanobisGater", "innovation_log_likelihoods"],
    "initiator": ["SingleMeasurementInitiator"],
    "measurement": ["PositionFix", "RangeAzimuth", "RangeBearingElevation"],
    "predictor": ["KalmanPredictor"],
    "reprocessing": ["ReprocessingHistory"],
    "roles": ["Deleter", "Gater", "Initiator", "MeasurementModel", "Predictor", "Reprocessor", "TransitionModel",
              "Updater"],
    "state": ["GaussianState"],
    "transition": ["ConstantPosition", "ConstantVelocity"],
    "updater": ["ExtendedKalmanUpdater", "KalmanUpdater", "kalman_update"],
})
