"""Mission state machine: idle -> dive -> survey -> surface -> done, abort on faults.

An abort (leaving the safe depth band, too close to the seabed, DVL bottom lock lost for
too long, no navigation, a dive or mission that takes too long) sends the vehicle to the
surface in state ``ABORT``; it ends in ``DONE`` with :attr:`MissionFsm.abort_reason` set.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

from autonomy.control.setpoint import Setpoint
from autonomy.guidance.config import MissionConfig
from autonomy.guidance.survey import SurveyGuidance
from autonomy.messages import NavEstimate


class MissionState(enum.Enum):
    IDLE = "idle"
    DIVE = "dive"
    SURVEY = "survey"
    SURFACE = "surface"
    ABORT = "abort"
    DONE = "done"


@dataclass(frozen=True, slots=True)
class Transition:
    t_s: float
    from_state: MissionState
    to_state: MissionState
    reason: str


class MissionFsm:
    """Sequences a survey and watches for faults.

    Call :meth:`update` at the autonomy rate with the mission time, the latest navigation
    estimate (None if the filter has produced none) and whether the DVL has bottom lock.
    It returns the autopilot setpoint for this step, or None while idle (thrusters off).
    """

    def __init__(self, cfg: MissionConfig, guidance: SurveyGuidance) -> None:
        self.cfg = cfg
        self.guidance = guidance
        self.reset()

    def reset(self) -> None:
        """Back to ``IDLE`` with no history (the guidance restarts when the dive ends)."""
        self.state = MissionState.IDLE
        self.abort_reason: str | None = None
        self.transitions: list[Transition] = []
        self._last_nav_t_s: float | None = None
        self._last_lock_t_s = 0.0
        self._state_since_s = 0.0
        self._settled_since_s: float | None = None
        self._yaw_rad = 0.0
        self._hold_heading_rad = 0.0

    @property
    def mode(self) -> str:
        """Current state name: idle, dive, survey, surface, abort or done; while surveying, the
        guidance's own ``mode_label`` (``inspect`` on an inspection leg)."""
        if self.state is MissionState.SURVEY:
            return self.guidance.mode_label
        return self.state.value

    @property
    def done(self) -> bool:
        return self.state is MissionState.DONE

    @property
    def aborted(self) -> bool:
        return self.abort_reason is not None

    @property
    def succeeded(self) -> bool:
        return self.done and self.abort_reason is None

    def _go(self, t_s: float, state: MissionState, reason: str) -> None:
        self.transitions.append(Transition(t_s, self.state, state, reason))
        self.state = state
        self._state_since_s = t_s
        self._settled_since_s = None
        self._hold_heading_rad = self._yaw_rad

    def abort(self, t_s: float, reason: str) -> None:
        """Abort now (also for faults detected outside the state machine)."""
        if self.state in (MissionState.ABORT, MissionState.DONE):
            return
        self.abort_reason = reason
        self._go(t_s, MissionState.ABORT, reason)

    def _check_faults(self, t_s: float, nav: NavEstimate | None, bottom_lock: bool) -> None:
        p = self.cfg
        if t_s > p.max_mission_time_s:
            self.abort(t_s, f"mission time {t_s:.1f} s exceeds max_mission_time_s {p.max_mission_time_s}")
            return
        if nav is None:
            last = self._last_nav_t_s if self._last_nav_t_s is not None else self._state_since_s
            if t_s - last > p.nav_timeout_s:
                self.abort(t_s, f"no navigation for more than nav_timeout_s {p.nav_timeout_s} s")
            return
        depth = float(nav.pos_ned[2])
        if depth > p.safe_depth_max_m:
            self.abort(t_s, f"depth {depth:.2f} m below safe_depth_max_m {p.safe_depth_max_m}")
            return
        if self.state is MissionState.SURVEY and depth < p.safe_depth_min_m:
            self.abort(t_s, f"depth {depth:.2f} m above safe_depth_min_m {p.safe_depth_min_m}")
            return
        if math.isfinite(nav.altitude_m) and nav.altitude_m < p.min_altitude_m:
            self.abort(t_s, f"altitude {nav.altitude_m:.2f} m below min_altitude_m {p.min_altitude_m}")
            return
        if self.state is MissionState.SURVEY and t_s - self._last_lock_t_s > p.bottom_lock_timeout_s:
            self.abort(t_s, f"DVL bottom lock lost for more than bottom_lock_timeout_s {p.bottom_lock_timeout_s} s")

    def _vertical_error_m(self, nav: NavEstimate) -> float:
        g = self.guidance
        if g.depth_m is not None:
            return abs(float(nav.pos_ned[2]) - g.depth_m)
        return abs(nav.altitude_m - g.altitude_m) if math.isfinite(nav.altitude_m) else math.inf

    def update(self, t_s: float, nav: NavEstimate | None, bottom_lock: bool) -> Setpoint | None:
        """Advance the state machine; return this step's setpoint (None while idle)."""
        p = self.cfg
        if nav is not None:
            self._last_nav_t_s = t_s
            self._yaw_rad = float(nav.rpy_rad[2])
        if bottom_lock:
            self._last_lock_t_s = t_s

        if self.state is MissionState.IDLE:
            if nav is not None and t_s >= p.start_delay_s:
                self._go(t_s, MissionState.DIVE, "start")
            else:
                return None

        if self.state in (MissionState.DIVE, MissionState.SURVEY):
            self._check_faults(t_s, nav, bottom_lock)

        if self.state is MissionState.DIVE:
            if t_s - self._state_since_s > p.dive_timeout_s:
                self.abort(t_s, f"dive not settled within dive_timeout_s {p.dive_timeout_s} s")
            elif nav is not None:
                if self._vertical_error_m(nav) <= p.dive_tolerance_m:
                    if self._settled_since_s is None:
                        self._settled_since_s = t_s
                    if t_s - self._settled_since_s >= p.dive_settle_s:
                        self._go(t_s, MissionState.SURVEY, "reached survey depth")
                        self._last_lock_t_s = t_s  # the lock timeout counts from here
                        self.guidance.start(nav.pos_ned[:2], float(nav.rpy_rad[2]))
                else:
                    self._settled_since_s = None
            if self.state is MissionState.DIVE:
                return Setpoint(0.0, self._hold_heading_rad, **self.guidance.vertical_setpoint())

        if self.state is MissionState.SURVEY:
            if nav is None:
                return Setpoint(0.0, self._hold_heading_rad, **self.guidance.vertical_setpoint())
            setpoint = self.guidance.update(nav)
            if not self.guidance.finished:
                return setpoint
            self._go(t_s, MissionState.SURFACE, "survey complete")

        if self.state in (MissionState.SURFACE, MissionState.ABORT):
            if nav is not None and float(nav.pos_ned[2]) <= p.surface_depth_m:
                self._go(t_s, MissionState.DONE, "surfaced")
            else:
                return Setpoint(0.0, self._hold_heading_rad, depth_m=0.0)

        return Setpoint(0.0, self._hold_heading_rad, depth_m=0.0)
