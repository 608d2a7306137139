"""What the mission loop emits: step records and sonar events, and the observer protocol.

Outputs (CSV, plots, rerun recordings, metrics) are observers reading these records;
they never take part in the loop's logic.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from numpy.typing import NDArray

from autonomy.messages import Detection, NavEstimate
from sim.truth import VehicleTruth

if TYPE_CHECKING:
    from sim.mission import Mission


@dataclass(frozen=True, slots=True)
class StepRecord:
    """State at one autonomy tick.

    Attributes:
        truth: true vehicle state.
        nav: navigation estimate the autonomy used.
        setpoint_speed_mps, setpoint_heading_rad, setpoint_altitude_m, setpoint_depth_m:
            what guidance asked for (NaN where unused).
        wrench_body: (6,) desired body wrench from the autopilots, N and N m.
        thruster_cmd: (n_thr,) normalised thruster commands in [-1, 1].
        mode: mission state-machine mode.
    """

    t_s: float
    truth: VehicleTruth
    nav: NavEstimate
    setpoint_speed_mps: float
    setpoint_heading_rad: float
    setpoint_altitude_m: float
    setpoint_depth_m: float
    wrench_body: NDArray[np.float64]
    thruster_cmd: NDArray[np.float64]
    mode: str


@dataclass(slots=True)
class FlsEvent:
    """One FLS frame with what perception made of it.

    ``render`` is the simulator's render (frame + ground truth); ``detections`` the
    ATR output; ``true_detection`` flags each detection matched to a visible target.
    """

    t_s: float
    render: Any
    detections: list[Detection] = field(default_factory=list)
    true_detection: list[bool] = field(default_factory=list)
    localized: list[Any] = field(default_factory=list)
    world_objects: list[Any] = field(default_factory=list)


class MissionObserver(Protocol):
    def on_start(self, mission: "Mission") -> None: ...

    def on_step(self, record: StepRecord) -> None: ...

    def on_fls(self, event: FlsEvent) -> None: ...

    def on_end(self, mission: "Mission") -> None: ...
