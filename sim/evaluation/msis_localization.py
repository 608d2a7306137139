"""Localisation error of a scanning-sonar mission against dead reckoning in the same run.

:class:`LocalizationErrorObserver` feeds a second navigation filter with every message the
mission's filter gets except the sonar position fixes (:class:`autonomy.messages.PositionFixMsg`),
the commanded wrench (for a DVL-free filter's speed model) taken from each step record:
the dead reckoning of the same run, same sensor noise, same path. At each step it records the
horizontal error of both against the true body position.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from autonomy.frames import wrap_angle
from autonomy.messages import PositionFixMsg, WrenchCmdMsg
from autonomy.msis.localization import tank_walls
from sim.events.records import MissionInfo, MissionSummary, ObserverBase, StepRecord


@dataclass
class LocalizationErrorObserver(ObserverBase):
    """Horizontal errors (m) of the mission's estimate and of a fix-free shadow filter.

    Args:
        make_nav_filter: scenario -> a fresh navigation filter at the start pose
            (:meth:`sim.mission.parts.MissionParts.make_nav_filter`): the shadow filter.
        localizer: the mission's scanning-sonar localiser (its wall estimates are scored; None:
            no wall figures).
        basin: the scenario's basin (``world.basin``: the true walls).
        t_start_s: errors are recorded from this time on.
    """

    sonar_truth = False  # reads no sonar ground truth (the sonar need not compute it)

    make_nav_filter: Callable[[Any], Any]
    localizer: Any = None
    basin: Any = None
    t_start_s: float = 0.0
    t_s: list[float] = field(default_factory=list)
    err_fused_m: list[float] = field(default_factory=list)
    err_dr_m: list[float] = field(default_factory=list)
    fixes: list[PositionFixMsg] = field(default_factory=list)
    dr_path_ne: list[np.ndarray] = field(default_factory=list)
    wall_angle_err_deg: dict[int, list[float]] = field(default_factory=dict)
    wall_angle_err_sonar_deg: dict[int, list[float]] = field(default_factory=dict)
    _heading_err_rad: list[float] = field(default_factory=list)

    def on_start(self, info: MissionInfo) -> None:
        self._dr = self.make_nav_filter(info.scenario)
        self._handlers = {t: h for t, h in self._dr.message_handlers().items() if t is not PositionFixMsg}

    def on_message(self, name: str, msg) -> None:
        if isinstance(msg, PositionFixMsg):
            self.fixes.append(msg)
            d_psi = float(np.mean(self._heading_err_rad)) if self._heading_err_rad else 0.0
            self._heading_err_rad = []
            self._note_walls(name, d_psi)
            return
        h = self._handlers.get(type(msg))
        if h is not None:
            h(msg)

    def on_step(self, rec: StepRecord) -> None:
        self._dr.predict(rec.t_s)
        self._dr.on_wrench_cmd(WrenchCmdMsg(rec.t_s, rec.wrench_body))  # as the mission's filter got it
        self._heading_err_rad.append(float(wrap_angle(rec.nav.rpy_rad[2] - rec.truth.rpy_rad[2])))
        dr = self._dr.estimate().pos_ned[:2]
        self.dr_path_ne.append(dr.copy())
        if rec.t_s < self.t_start_s:
            return
        true = rec.truth.pos_ned[:2]
        self.t_s.append(rec.t_s)
        self.err_fused_m.append(float(np.linalg.norm(rec.nav.pos_ned[:2] - true)))
        self.err_dr_m.append(float(np.linalg.norm(dr - true)))

    def on_end(self, summary: MissionSummary) -> None:
        pass

    def _note_walls(self, name: str, d_psi: float) -> None:
        """Angle error (deg) of the latest wall fix's fused estimate of each wall (one per wall
        and fix) against the true wall, per wall index: as placed in the navigation frame, and
        with the navigation's heading error (its mean since the last fix: the points of a sweep
        are placed with it) taken out, the sonar processing's own error."""
        loc, basin = self.localizer, self.basin
        if loc is None or loc.cfg.method != "walls" or basin is None:
            return
        walls = tank_walls(np.asarray(basin.center_ne_m, float), np.asarray(basin.size_ne_m, float))
        for i, s in loc.last_walls.items():
            n_w = walls[i][0]
            n_s = s.normal if s.normal @ n_w >= 0.0 else -s.normal
            ang = np.degrees(np.arctan2(n_w[0] * n_s[1] - n_w[1] * n_s[0], n_s @ n_w))
            self.wall_angle_err_deg.setdefault(i, []).append(float(abs(ang)))
            self.wall_angle_err_sonar_deg.setdefault(i, []).append(float(abs(ang - np.degrees(d_psi))))

    def rms(self) -> dict[str, float]:
        """RMS and final horizontal errors (m) of the fused estimate and of dead reckoning."""
        f, d = np.asarray(self.err_fused_m), np.asarray(self.err_dr_m)
        walls = {f"wall{i}_median_angle_err_deg": float(np.median(v)) for i, v in sorted(self.wall_angle_err_deg.items())}
        walls.update({f"wall{i}_max_angle_err_deg": float(np.max(v)) for i, v in sorted(self.wall_angle_err_deg.items())})
        walls.update({f"wall{i}_max_angle_err_sonar_deg": float(np.max(v))
                      for i, v in sorted(self.wall_angle_err_sonar_deg.items())})
        walls.update({f"wall{i}_seen_fixes": len(v) for i, v in sorted(self.wall_angle_err_deg.items())})
        return {**walls, "rms_fused_m": float(np.sqrt(np.mean(f ** 2))), "rms_dead_reckoning_m": float(np.sqrt(np.mean(d ** 2))),
                "final_fused_m": float(f[-1]), "final_dead_reckoning_m": float(d[-1]), "n_fixes": len(self.fixes)}
