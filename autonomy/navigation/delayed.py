"""Late position fixes fused at their measurement time: a stored history and re-processing.

A fix that reaches the vehicle ``tau`` seconds after it was measured (a USBL fix computed on
the surface and sent down an acoustic link: the USBL's own delay, the slot wait and the
packet time, several seconds) describes where the vehicle WAS. Applying it at the filter
time, as :class:`autonomy.navigation.ekf.NavigationFilter` does for any message stamped
earlier, pulls the estimate back along the track by ``speed * tau`` (2.5 m at 0.5 m/s and
5 s). :class:`DelayedFixFilter` wraps the filter, records every message and prediction it
processes and keeps copies of the filter's state every ``snapshot_every_s``. A late fix
rolls the filter back to the last copy before its measurement time, replays the recorded
events up to that time, fuses the fix there and replays the rest: the result is the
estimate the filter would have had with the fix on time (exactly, for the same sequence of
events): the re-processing solution to out-of-sequence measurements ([BarShalom2001-OOSM]
section 10.8, docs/references.md), through the shared
:class:`autonomy.estimation.reprocessing.ReprocessingHistory`, as the target tracker does for its
late USBL fixes.

Fixes older than the history (``horizon_s``) are refused. The wrapper has the filter's
interface (``predict``, ``estimate``, ``message_handlers``, ``t_s``, ``state``,
``covariance``), so the mission loop drives either one.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from autonomy.estimation.gater import mahalanobis2
from autonomy.estimation.reprocessing import ReprocessingHistory
from autonomy.messages import NavEstimate, PositionFixMsg
from autonomy.navigation.ekf import NavigationFilter

_PREDICT = "predict"
_LATE_FIX = "late_fix"


class DelayedFixFilter:
    """A :class:`NavigationFilter` that fuses late position fixes at their measurement time.

    Args:
        nav: the filter to wrap (owned by the wrapper from now on: feed it only through here).
        horizon_s: history kept, s; older fixes are refused.
        snapshot_every_s: filter time between stored copies of its state, s (replay cost per
            fix: up to this much of extra events).
        gate_chi2: innovation gate of the late fixes (2 dof, north/east; None: none).

    Attributes:
        n_late_fused, n_late_gated, n_late_too_old: late fixes fused, refused (by the gate or
            the filter's mode), refused for being older than the history.
    """

    def __init__(self, nav: NavigationFilter, *, horizon_s: float = 60.0, snapshot_every_s: float = 1.0,
                 gate_chi2: float | None = 13.8) -> None:
        if not (horizon_s > 0.0 and snapshot_every_s > 0.0):
            raise ValueError(f"horizon_s and snapshot_every_s must be > 0, got {horizon_s}, {snapshot_every_s}")
        self.nav = nav
        self.horizon_s = float(horizon_s)
        self.snapshot_every_s = float(snapshot_every_s)
        self.gate_chi2 = gate_chi2
        self._methods = {_PREDICT: nav.predict, _LATE_FIX: self._fuse}
        handlers = nav.message_handlers()
        self._methods.update({fn.__name__: fn for fn in handlers.values()})
        self._handlers = {t: self._recording(fn.__name__) for t, fn in handlers.items()}
        # events: (method name, argument), re-run in order from the last copy of the filter's state
        self._history: ReprocessingHistory[tuple[str, Any], dict[str, Any]] = ReprocessingHistory(
            self._apply, self._copy_state, self._restore, lambda: self.nav.t_s,
            checkpoint_every_s=self.snapshot_every_s, keep_s=self.horizon_s + self.snapshot_every_s)
        self.n_late_fused = self.n_late_gated = self.n_late_too_old = 0

    # ------------------------------------------------------------------ the filter's interface
    @property
    def t_s(self) -> float:
        return self.nav.t_s

    @property
    def state(self) -> np.ndarray:
        return self.nav.state

    @property
    def covariance(self) -> np.ndarray:
        return self.nav.covariance

    def estimate(self) -> NavEstimate:
        return self.nav.estimate()

    def predict(self, t_s: float) -> None:
        self._history.append((_PREDICT, float(t_s)))

    def message_handlers(self) -> dict[type, Callable[[Any], Any]]:
        """The filter's handlers, each recording its message for re-processing."""
        return dict(self._handlers)

    # ------------------------------------------------------------------ late fixes
    def on_late_fix(self, msg: PositionFixMsg) -> bool:
        """Fuse a north/east fix of the body origin measured at ``msg.t_s`` (at or before the
        filter time). Returns whether it was fused (inside the history and the gate)."""
        t_m = float(msg.t_s)
        if t_m < self.nav.t_s - self.horizon_s:
            self.n_late_too_old += 1
            return False
        try:
            fused = self._history.insert((_LATE_FIX, msg), t_m)
        except ValueError:  # older than the oldest copy kept
            self.n_late_too_old += 1
            return False
        if fused:
            self.n_late_fused += 1
        else:
            self.n_late_gated += 1
        return fused

    # ------------------------------------------------------------------ internals
    def _recording(self, name: str) -> Callable[[Any], Any]:
        def handle(msg: Any) -> Any:
            return self._history.append((name, msg))
        return handle

    def _apply(self, event: tuple[str, Any]) -> Any:
        return self._methods[event[0]](event[1])

    def _fuse(self, msg: PositionFixMsg) -> bool:
        nav = self.nav
        nav.predict(msg.t_s)
        if self.gate_chi2 is not None:
            r = np.asarray(msg.pos_ne_m, dtype=float) - nav.state[:2]
            S = nav.covariance[:2, :2] + np.asarray(msg.cov_ne_m2, dtype=float).reshape(2, 2)
            if mahalanobis2(r, S) > self.gate_chi2:
                return False
        return nav.on_position_fix(msg)

    def _copy_state(self) -> dict[str, Any]:
        """The filter's mutable state: its arrays copied, its scalars (its models and
        configuration are never changed after construction)."""
        return {k: v.copy() if isinstance(v, np.ndarray) else v for k, v in vars(self.nav).items()}

    def _restore(self, state: dict[str, Any]) -> None:
        vars(self.nav).update({k: v.copy() if isinstance(v, np.ndarray) else v for k, v in state.items()})
