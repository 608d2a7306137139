"""Inspection-planner re-plan benchmark (``auvsim bench inspection``).

Synthetic world models: ``n`` confirmed objects scattered over a 40 m x 40 m survey area,
each with an anisotropic covariance and one to three recorded aspects, none confident, so
every re-plan chooses a heading for every object and orders them all (the exact tour up to
the planner's ``exact_tour_max`` legs, 2-opt above). Each re-plan is what the guidance does
at a world-model update (:meth:`autonomy.guidance.inspection.InspectionGuidance.on_world_model`:
record the looks, plan the tour), timed in process CPU time on one core; each is repeated
``repeats`` times and the fastest kept (as ``timeit`` does), the single-shot p99 beside it.
Goal: p99 <= 10 ms per re-plan.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from autonomy.guidance.config import InspectionConfig, LosConfig, SurveyConfig
from autonomy.guidance.inspection import InspectionGuidance
from autonomy.guidance.inspection_planner import PlannerParams

GOAL_REPLAN_MS_P99 = 10.0


@dataclass(frozen=True)
class _Obj:
    id: int
    class_pmf: np.ndarray
    pos_ned: np.ndarray
    cov_ned: np.ndarray
    n_detections: int
    existence_probability: float

    @property
    def class_name(self) -> str:
        return "target" if self.class_pmf[0] >= 0.5 else "not_target"


def _objects(n: int, rng: np.random.Generator, n_det: int) -> list[_Obj]:
    out = []
    for i in range(n):
        a = rng.uniform(0, math.pi)
        R = np.array([[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]])
        cov = R @ np.diag([rng.uniform(0.2, 0.6) ** 2, rng.uniform(0.05, 0.2) ** 2, 0.01]) @ R.T
        out.append(_Obj(i, np.array([0.95, 0.05]), np.array([rng.uniform(-20, 20), rng.uniform(-20, 20), 10.0]), cov,
                        n_det, 0.995))
    return out


def measure(n_objects: int, seed: int = 0, replans: int = 60, repeats: int = 3) -> dict:
    """Re-plan cost with ``n_objects`` uncertain objects, ``replans`` world-model updates."""
    rng = np.random.default_rng(seed)
    survey = SurveyConfig(origin_ne_m=(20.0, -20.0), leg_heading_deg=90.0, length_m=40.0, width_m=40.0)
    cfg = InspectionConfig(enabled=True, coverage_spacing_m=20.0, look_2sigma_m=0.01, max_legs_per_object=100)
    guidance = InspectionGuidance.from_config(survey, cfg, LosConfig())
    guidance.start((25.0, -25.0), 0.0)
    guidance.phase = "inspect"
    best_ms, single_ms, n_legs = [], [], []
    for k in range(replans):
        objs = _objects(n_objects, np.random.default_rng(seed * 1000 + k % 7), 10 + k)
        guidance._pos = rng.uniform(-20, 20, 2)
        best = math.inf
        for r in range(repeats):
            t0 = time.process_time()
            guidance.on_world_model(float(k), objs)
            dt = (time.process_time() - t0) * 1e3
            best = min(best, dt)
            if r == 0:
                single_ms.append(dt)
        best_ms.append(best)
        n_legs.append(len(guidance.planned))
    b = np.asarray(best_ms)
    return {"n_objects": n_objects, "legs_planned_mean": float(np.mean(n_legs)),
            "replan_ms_p50": round(float(np.percentile(b, 50)), 3), "replan_ms_p99": round(float(np.percentile(b, 99)), 3),
            "replan_ms_p99_single_shot": round(float(np.percentile(single_ms, 99)), 3),
            "exact_tour": n_objects <= guidance.planner.params.exact_tour_max}


def run(table_objects: tuple[int, ...] = (3, 6, 7, 8, 12, 24, 48), seed: int = 0) -> dict:
    """The re-plan cost table over 3 to 48 uncertain objects (the shipped layouts hold 3-12);
    the headline is the worst p99 over the whole table."""
    table = [measure(n, seed) for n in table_objects]
    worst = max(r["replan_ms_p99"] for r in table)
    worst_single = max(r["replan_ms_p99_single_shot"] for r in table)
    return {"replan_ms_p99_worst": worst, "replan_ms_p99_single_shot_worst": worst_single,
            "goal_replan_ms_p99": GOAL_REPLAN_MS_P99, "meets_goal": worst <= GOAL_REPLAN_MS_P99,
            "objects_range": [min(table_objects), max(table_objects)], "table": table,
            "note": "process CPU time per re-plan (look bookkeeping, a heading per object, the tour); replan_ms_*: "
                    "the fastest of 3 repeats of each re-plan (what the code costs), *_single_shot: the first try "
                    "(what a busy machine adds); exact Held-Karp tour up to "
                    f"{PlannerParams().exact_tour_max} legs, nearest neighbour + 2-opt above"}


if __name__ == "__main__":
    import json

    print(json.dumps(run(), indent=2))
