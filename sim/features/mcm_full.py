"""The ``mcm_survey`` full mode as a mission feature ([P003]): the side-scan pings form tile
pairs onboard and the highlight-shadow detector reports each tile; after the run the mappers
and scores of the kinematic mode run on the tiles.

Files: this module, :mod:`sim.mcm.full_mode` (the onboard tile processing and the recording
observer), :mod:`sim.mcm.survey` (mapping and scores), :mod:`sim.mcm.figures`.
Config: ``mcm`` (``mode: full``).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from sim.features.base import FeatureContext, LoopPorts, MissionFeature
from sim.outputs.json_files import write_json
from sim.features.base import fmt_or_na as _fmt
from sim.events.records import MissionObserver
from sim.mcm.full_mode import McmFullObserver, SssTileProcessor, no_tile_message
from sim.mcm.figures import confirmed_objects_overlay, summarise, write_figures


class McmFullFeature(MissionFeature):
    """Onboard side-scan tiles and detections; the mapping results of a run.

    Attributes:
        processor: the :class:`sim.mcm.full_mode.SssTileProcessor`.
        recorder: the run's :class:`sim.mcm.full_mode.McmFullObserver` (None outside a run's outputs).
        result: the mapping results after :meth:`add_metrics` (None: no tile formed).
    """

    name = "mcm_full"

    def __init__(self, ctx: FeatureContext) -> None:
        self.ctx = ctx
        self.processor = SssTileProcessor(ctx.scenario)
        self.recorder: Any = None
        self.result: dict | None = None

    @classmethod
    def build(cls, ctx: FeatureContext) -> McmFullFeature | None:
        return cls(ctx) if ctx.scenario.mcm.mode == "full" else None

    def reset(self, ports: LoopPorts) -> None:
        self.processor.reset()
        ports.process_source(self.ctx.scenario.mcm.sensor, self.processor)

    # -- a run's outputs -------------------------------------------------------------------
    def observers(self, options: Mapping[str, Any]) -> list[MissionObserver]:
        self.recorder = McmFullObserver(self.ctx.scenario)
        return [self.recorder]

    def add_metrics(self, metrics: dict[str, Any], log: Any) -> None:
        if self.recorder is None:
            return
        if not self.recorder.tiles:  # too short a run: its other outputs still count

            metrics["mcm"] = {"tiles": 0, "note": no_tile_message(self.ctx.scenario)}
            return

        self.result = self.recorder.results(self.ctx.seed)
        metrics["mcm"] = {**summarise([self.result]), "detector": self.result["detector"]}

    def map_layers(self, layers: dict[str, Any]) -> None:
        if self.result is not None:
            overlay = confirmed_objects_overlay(self.result)  # None: no object confirmed
            if overlay is not None:
                layers["overlays"].append(overlay)

    def write_outputs(self, out_dir: Path, metrics: dict[str, Any], title: str) -> None:
        if self.result is not None:
            write_json(out_dir / "mcm.json", self.result)
            write_figures(out_dir, [self.result], title=title)

    @classmethod
    def summary_lines(cls, metrics: Mapping[str, Any]) -> list[str]:
        if "mcm" not in metrics:
            return []
        mcm = metrics["mcm"]
        if "note" in mcm:
            return [mcm["note"]]
        det = mcm["detector"]
        maps = ", ".join(f"{k} GOSPA {_fmt(v['final_gospa_mean'], '.1f')} ({v['final_cardinality_mean']:.0f} objects)"
                         for k, v in mcm.items() if isinstance(v, dict) and "final_gospa_mean" in v)
        return [f"mcm: {det['tiles']} tiles, detector pd {_fmt(det['pd'], '.2f')}, "
                f"{det['clutter_per_tile']:.2f} false per tile; {maps}"]
