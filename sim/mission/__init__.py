"""The mission loop: :class:`Mission` (the fixed loop, :mod:`sim.mission.loop`), the core parts
it is built from (:mod:`sim.mission.parts`) and the protocol studies plug in with
(:mod:`sim.features.base`, beside the studies in :mod:`sim.features`)."""

from sim.mission.loop import Mission
from sim.mission.parts import NAV_SOURCES
from sim.events.records import MissionSummary

__all__ = ["NAV_SOURCES", "Mission", "MissionSummary"]
