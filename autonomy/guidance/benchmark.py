"""Per-call cost of the guidance, mission and autopilot stack (for ``auvsim bench``)."""

from __future__ import annotations

import math
import time

import numpy as np

from autonomy.control.allocation import ThrusterLayout, allocate
from autonomy.control.autopilot import Autopilot
from autonomy.control.config import ControlConfig
from autonomy.guidance.config import LosConfig, MissionConfig
from autonomy.guidance.lawnmower import plan_lawnmower
from autonomy.guidance.mission import MissionFsm
from autonomy.guidance.survey import SurveyGuidance
from autonomy.messages import NavEstimate


def bench_guidance_control(n_calls: int = 2000) -> dict[str, float]:
    """Time ``n_calls`` autonomy steps of a lawnmower survey on synthetic navigation.

    Returns a dict with the mean wall time per call (microseconds) of
    ``SurveyGuidance.update`` via ``MissionFsm.update``, ``Autopilot.update`` and the thrust
    allocation ``allocate`` (FeelHippo-like 4-thruster layout), and their sum per step.
    """
    plan = plan_lawnmower((0.0, 0.0), 30.0, 16.0, 0.0, 4.0)
    guidance = SurveyGuidance(plan.waypoints_ne_m, 0.5, LosConfig(), altitude_m=2.0)
    fsm = MissionFsm(MissionConfig(dive_settle_s=0.0), guidance)
    autopilot = Autopilot(ControlConfig())
    layout = ThrusterLayout(
        names=("surge_port", "surge_stbd", "sway", "heave"),
        pos_body_m=np.array([[-0.22, -0.26, 0.0], [-0.22, 0.26, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, -0.1]]),
        dir_body=np.array([[1.0, 0, 0], [1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]]),
        max_fwd_n=25.0, max_rev_n=20.0, dead_zone=0.05, curve_exponent=1.5,
    )
    navs = [
        NavEstimate(t_s=0.1 * k, pos_ned=np.array([0.05 * k % 30.0, 0.3 * math.sin(0.01 * k), 2.0]),
                    rpy_rad=np.array([0.0, 0.0, 0.02 * math.sin(0.05 * k)]),
                    vel_body_mps=np.array([0.5, 0.01, 0.0]), rate_body_radps=np.zeros(3),
                    cov_pos_ned=np.eye(3) * 0.01, altitude_m=2.0)
        for k in range(n_calls)
    ]
    t0 = time.perf_counter()
    setpoints = [fsm.update(nav.t_s, nav, True) for nav in navs]
    t1 = time.perf_counter()
    wrenches = [autopilot.update(nav, sp, 0.1) for nav, sp in zip(navs, setpoints)]
    t2 = time.perf_counter()
    for w in wrenches:
        allocate(w, layout)
    t3 = time.perf_counter()
    us = 1e6 / n_calls
    out = {
        "calls": float(n_calls),
        "mission_guidance_us": (t1 - t0) * us,
        "autopilot_us": (t2 - t1) * us,
        "allocation_us": (t3 - t2) * us,
    }
    out["total_per_step_us"] = out["mission_guidance_us"] + out["autopilot_us"] + out["allocation_us"]
    return out
