"""The studies of the mission loop, one feature module each (:class:`sim.features.base.MissionFeature`).

:data:`FEATURES` is the order in which the loop calls them at each hook and in which they add
their metrics and summary lines. A new study adds its module here and its config; nothing else
in the loop, the outputs or the CLI changes.

=====================================  ==========================================================
feature                                what it adds
=====================================  ==========================================================
:class:`SurveyPerceptionFeature`       ATR -> geolocalisation -> world model on the sonar's frames
:class:`InspectionFeature`             the world model's updates to the inspection guidance; its legs
:class:`SeaTrialFeature`               extra vehicles (the buoy), the acoustic link, the surface
                                       world model, late USBL fixes in the AUV's filter
:class:`MsisLocalizationFeature`       Ping360 pool / tank localisation fixes
:class:`TrackingFeature`               diver / vehicle tracking, buddy guidance
:class:`McmFullFeature`                side-scan tiles, detections, mapping (``mcm.mode: full``)
=====================================  ==========================================================
"""

from __future__ import annotations

from sim.features.inspection import InspectionFeature
from sim.features.mcm_full import McmFullFeature
from sim.features.msis_localization import MsisLocalizationFeature
from sim.features.sea_trial import SeaTrialFeature
from sim.features.survey_perception import SurveyPerceptionFeature
from sim.features.tracking import TrackingFeature
from sim.features.base import FeatureContext, MissionFeature

#: Every feature, in the order the loop calls them.
FEATURES: tuple[type[MissionFeature], ...] = (
    SurveyPerceptionFeature, InspectionFeature, SeaTrialFeature, MsisLocalizationFeature, TrackingFeature, McmFullFeature)


def build_features(ctx_args: dict, extra: tuple[type[MissionFeature], ...] = ()) -> tuple[MissionFeature, ...]:
    """The features of one mission, in :data:`FEATURES` order then ``extra``'s (each sees those
    built before it).

    Args:
        ctx_args: the :class:`sim.features.base.FeatureContext` fields but ``features``.
        extra: feature classes of the caller's own (a study outside the package), after the shipped ones.

    Raises:
        TypeError: an ``extra`` entry that is not a MissionFeature subclass (an instance, say).
        ValueError: more than one feature drives the guidance.
    """
    for cls in extra:
        if not (isinstance(cls, type) and issubclass(cls, MissionFeature)):
            raise TypeError(f"features: expected MissionFeature subclasses (the loop builds each with "
                            f"cls.build(ctx)), got {cls!r}")
    built: dict[type, MissionFeature] = {}
    for cls in (*FEATURES, *extra):
        feature = cls.build(FeatureContext(**ctx_args, features=dict(built)))
        if feature is not None:
            built[cls] = feature
    drivers = [f.name for f in built.values() if f.drives_guidance]
    if len(drivers) > 1:
        raise ValueError(f"more than one feature drives the guidance: {', '.join(drivers)}")
    return tuple(built.values())


def summary_lines(metrics: dict, extra: tuple[type[MissionFeature], ...] = ()) -> list[str]:
    """Every feature's console summary lines for ``metrics`` (metrics.json), in order (the
    shipped features, then ``extra``'s)."""
    return [line for cls in (*FEATURES, *extra) for line in cls.summary_lines(metrics)]


def runs_to_duration(scenario, extra: tuple[type[MissionFeature], ...] = ()) -> bool:
    """Whether ``scenario``'s mission runs to ``duration_s`` by design (no survey to finish)."""
    return any(cls.runs_to_duration(scenario) for cls in (*FEATURES, *extra))


__all__ = ["FEATURES", "FeatureContext", "InspectionFeature", "McmFullFeature", "MissionFeature", "MsisLocalizationFeature", "SeaTrialFeature", "SurveyPerceptionFeature",
           "TrackingFeature", "build_features", "runs_to_duration", "summary_lines"]
