"""A second navigation filter beside the mission's, fed the same sensor messages but not the
surface vehicle's USBL fixes: the DVL-only estimate of the same run, for comparing the
navigation error with and without the fixes on identical sensor data.

:class:`DvlOnlyBaseline` is a mission observer: it builds a fresh filter at the start pose
(:meth:`sim.mission.parts.MissionParts.make_nav_filter`), hands every delivered message the
filter handles to it (the fixes from the acoustic link excepted), predicts it to each
step's time and records its and the mission's horizontal errors against the truth.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from autonomy.messages import PositionFixMsg
from sim.comms.vehicle_link import FIX_SOURCE
from sim.events.records import MissionInfo, ObserverBase, StepRecord


class DvlOnlyBaseline(ObserverBase):
    """Observer running the DVL-only navigation filter of a mission.

    Args:
        make_nav_filter: scenario -> a fresh navigation filter at the start pose (called at
            :meth:`on_start`; :meth:`sim.mission.parts.MissionParts.make_nav_filter`).

    Attributes:
        t_s, mode: (n,) step times (s) and mission modes.
        err_fused_m, err_dvl_only_m: (n,) horizontal error of the mission's estimate and of
            the DVL-only one against the truth at each step, m.
    """

    sonar_truth = False  # reads no sonar ground truth (the sonar need not compute it)

    def __init__(self, make_nav_filter: Any) -> None:
        self.make_nav_filter = make_nav_filter
        self._nav = None

    def on_start(self, info: MissionInfo) -> None:
        self._nav = self.make_nav_filter(info.scenario)
        self._handlers = self._nav.message_handlers()
        self.t_s: list[float] = []
        self.mode: list[str] = []
        self.err_fused_m: list[float] = []
        self.err_dvl_only_m: list[float] = []

    def on_message(self, name: str, msg: Any) -> None:
        if isinstance(msg, PositionFixMsg) and msg.source == FIX_SOURCE:
            return
        handler = self._handlers.get(type(msg))
        if handler is not None:
            handler(msg)

    def on_step(self, r: StepRecord) -> None:
        self._nav.predict(r.t_s)
        truth = np.asarray(r.truth.pos_ned[:2], dtype=float)
        self.t_s.append(r.t_s)
        self.mode.append(r.mode)
        self.err_fused_m.append(float(np.linalg.norm(np.asarray(r.nav.pos_ned[:2]) - truth)))
        self.err_dvl_only_m.append(float(np.linalg.norm(self._nav.estimate().pos_ned[:2] - truth)))

    def on_end(self, summary: Any) -> None:
        pass

    def mean_errors_m(self, mode: str | None = "survey") -> tuple[float, float]:
        """Mean horizontal error (m) of the mission's estimate and of the DVL-only one over
        the steps in ``mode`` (None: every step); NaN when there are none."""
        keep = np.array([mode is None or m == mode for m in self.mode], dtype=bool)
        if not keep.any():
            return float("nan"), float("nan")
        return (float(np.mean(np.asarray(self.err_fused_m)[keep])),
                float(np.mean(np.asarray(self.err_dvl_only_m)[keep])))
