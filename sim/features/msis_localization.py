"""Scanning-sonar (Ping360) localisation in a pool or tank as a mission feature ([P002]): the
localiser takes each ping (never its truth) and may return a position fix, which the
navigation filter fuses.

Files: this module, :mod:`autonomy.msis.localization` (the onboard localiser),
:mod:`sim.evaluation.msis_localization` (errors against dead reckoning of the same run),
:mod:`sim.outputs.msis_overlay` (the map). Config: ``autonomy.msis_localization``, the
``msis`` sensor, ``world.basin``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from autonomy.msis.localization import MsisLocalizer
from sim.evaluation.msis_localization import LocalizationErrorObserver
from sim.features.base import FeatureContext, LoopPorts, MissionFeature
from sim.features.base import fmt_or_na as _fmt
from sim.events.records import MissionObserver
from sim.rng import component_rng
from sim.outputs.msis_overlay import basin_outline_ne, msis_overlay


class MsisLocalizationFeature(MissionFeature):
    """The localiser on the first scanning sonar's pings.

    Attributes:
        sensor: the scanning sonar's entry name.
        localizer: the :class:`autonomy.msis.localization.MsisLocalizer`.
        evaluation: the run's :class:`sim.evaluation.msis_localization.LocalizationErrorObserver` (None
            outside a run's outputs).
    """

    name = "msis_localization"

    def __init__(self, ctx: FeatureContext, sensor: str) -> None:
        self.ctx, self.sensor = ctx, sensor
        self.localizer = MsisLocalizer(ctx.scenario.autonomy.msis_localization,
                                       component_rng(ctx.seed, f"{sensor}_localizer"))
        self.evaluation: Any = None

    @classmethod
    def build(cls, ctx: FeatureContext) -> MsisLocalizationFeature | None:
        msis = next((s for s in ctx.parts.sensors.values() if s.kind == "msis"), None)
        if msis is None or ctx.scenario.autonomy.msis_localization.method == "none":
            return None
        return cls(ctx, msis.name)

    def reset(self, ports: LoopPorts) -> None:
        self.localizer.reset()
        ports.process_source(self.sensor, self._process)

    def _process(self, render: Any, nav: Any) -> Any:
        return self.localizer.process(render.ping, nav)  # the ping, never its truth

    # -- a run's outputs -------------------------------------------------------------------
    def error_observer(self) -> MissionObserver:
        """A fresh :class:`sim.evaluation.msis_localization.LocalizationErrorObserver` of this mission."""
        return LocalizationErrorObserver(self.ctx.parts.make_nav_filter, self.localizer, self.ctx.scenario.world.basin)

    def observers(self, options: Mapping[str, Any]) -> list[MissionObserver]:
        self.evaluation = self.error_observer()
        return [self.evaluation]

    def add_metrics(self, metrics: dict[str, Any], log: Any) -> None:
        if self.evaluation is not None and self.evaluation.err_fused_m:
            metrics["msis_localization"] = self.evaluation.rms()

    def map_layers(self, layers: dict[str, Any]) -> None:
        if self.evaluation is not None and self.evaluation.err_fused_m:
            basin = self.ctx.scenario.world.basin
            layers["overlays"].append(msis_overlay(self.evaluation, basin, self.localizer))
            layers["extents"].append(basin_outline_ne(basin))

    @classmethod
    def summary_lines(cls, metrics: Mapping[str, Any]) -> list[str]:
        if "msis_localization" not in metrics:
            return []
        ml = metrics["msis_localization"]
        return [f"msis localisation: {ml['n_fixes']} sonar position fix{'' if ml['n_fixes'] == 1 else 'es'}, "
                f"horizontal RMS error {_fmt(ml.get('rms_fused_m'), '.2f', ' m')} (dead reckoning alone "
                f"{_fmt(ml.get('rms_dead_reckoning_m'), '.2f', ' m')})"]
