"""Estimation roles shared by the world model, trackers and mappers.

Transition models, measurement models, predictor, updater, gater, data associator,
same-scan clusterer, initiator and deleter, each a small swappable part checked alone against an oracle (the
split of the Stone Soup tracking framework, https://stonesoup.readthedocs.io).
"""

from autonomy.estimation.assignment import murty_k_best, ranked_associations
from autonomy.estimation.association import KBestAssociator
from autonomy.estimation.clustering import cluster_consistent, fuse_cluster
from autonomy.estimation.deleter import UpdateTimeDeleter
from autonomy.estimation.gater import MahalanobisGater, innovation_log_likelihoods
from autonomy.estimation.initiator import SingleMeasurementInitiator
from autonomy.estimation.measurement import PositionFix, RangeAzimuth, RangeBearingElevation
from autonomy.estimation.predictor import KalmanPredictor
from autonomy.estimation.transition import ConstantPosition, ConstantVelocity
from autonomy.estimation.updater import ExtendedKalmanUpdater, KalmanUpdater

__all__ = [
    "ConstantPosition",
    "ConstantVelocity",
    "ExtendedKalmanUpdater",
    "KBestAssociator",
    "KalmanPredictor",
    "KalmanUpdater",
    "MahalanobisGater",
    "PositionFix",
    "RangeAzimuth",
    "RangeBearingElevation",
    "SingleMeasurementInitiator",
    "UpdateTimeDeleter",
    "cluster_consistent",
    "fuse_cluster",
    "innovation_log_likelihoods",
    "murty_k_best",
    "ranked_associations",
]
