"""Inspection guidance flown by a kinematic vehicle over a simulated world model: the phases,
a false alarm never aimed at, the interleaved mode's break-off and resume, the time budget."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from autonomy.guidance.config import InspectionConfig, LosConfig, SurveyConfig
from autonomy.guidance.inspection import InspectionGuidance, rejoin_path
from autonomy.messages import NavEstimate

SURVEY = SurveyConfig(origin_ne_m=(8.0, 0.0), leg_heading_deg=90.0, length_m=32.0, width_m=16.0, speed_mps=0.5,
                      altitude_m=2.0)


@dataclass(frozen=True)
class Obj:
    id: int
    pos_ned: np.ndarray
    existence_probability: float = 0.999
    n_detections: int = 0
    cov_ned: np.ndarray = field(default_factory=lambda: np.diag([0.04, 0.04, 0.01]))
    class_pmf: np.ndarray = field(default_factory=lambda: np.array([0.999, 0.001]))

    @property
    def class_name(self) -> str:
        return "target"


def nav(t_s: float, pos: np.ndarray, yaw: float) -> NavEstimate:
    return NavEstimate(t_s=t_s, pos_ned=np.array([pos[0], pos[1], 2.0]), rpy_rad=np.array([0.0, 0.0, yaw]),
                       vel_body_mps=np.array([0.5, 0.0, 0.0]), rate_body_radps=np.zeros(3),
                       cov_pos_ned=np.eye(3) * 0.01, cov_yaw_rad2=1e-4, altitude_m=2.0)


def fly(guidance: InspectionGuidance, objects: list[Obj], t_end_s: float = 900.0, frame_hz: float = 3.0):
    """A vehicle that turns at 0.3 rad/s towards the setpoint heading and moves at the setpoint
    speed; the sonar 'detects' an object inside 130 deg and 4.5-25 m ground range (a frame at
    ``frame_hz``). Returns the goals (object ids) the guidance aimed at and the path."""
    pos, yaw, dt = np.array([8.0, 0.0]), math.radians(90.0), 0.1
    guidance.start(pos, yaw)
    aimed, path = [], []
    next_frame = 0.0
    t = 0.0
    while t < t_end_s and not guidance.finished:
        if t >= next_frame:
            next_frame += 1.0 / frame_hz
            for k, o in enumerate(objects):
                d = o.pos_ned[:2] - pos
                g = float(np.hypot(*d))
                rel = abs(math.remainder(math.atan2(d[1], d[0]) - yaw, 2 * math.pi))
                if 4.5 <= g <= 25.0 and rel <= math.radians(65.0):
                    objects[k] = replace(o, n_detections=o.n_detections + 1)
            guidance.on_world_model(t, list(objects))
        sp = guidance.update(nav(t, pos, yaw))
        err = math.remainder(sp.heading_rad - yaw, 2 * math.pi)
        yaw += float(np.clip(err, -0.3 * dt, 0.3 * dt))
        pos = pos + sp.speed_mps * dt * np.array([math.cos(yaw), math.sin(yaw)])
        if guidance.leg is not None and (not aimed or aimed[-1] != guidance.leg.object_id):
            aimed.append(guidance.leg.object_id)
        path.append(pos.copy())
        t += dt
    return aimed, np.array(path), t


def test_coverage_then_inspection_then_done():
    cfg = InspectionConfig(enabled=True)
    g = InspectionGuidance.from_config(SURVEY, cfg, LosConfig(), swath_width_m=53.7)
    objects = [Obj(0, np.array([-7.0, 12.0, 4.0])), Obj(1, np.array([6.0, 24.0, 4.0]))]
    aimed, path, t = fly(g, objects)
    assert g.finished and t < 900.0
    events = [e.event for e in g.events]
    assert events[0] == "coverage_done" and events[-1] == "done"
    assert set(aimed) <= {0, 1} and aimed, "the objects seen only from the centre line at long range get legs"
    assert "all confident" in events and g.confident_t_s is not None
    # the coverage leg is the centre line N = 0 (the swath covers the 16 m width)
    assert np.allclose(g.plan.leg_starts_ne_m[:, 0], 0.0)
    # every position stays inside the area grown by the margin plus the turning overshoot
    loc = g.planner.area.local_m(path)
    assert loc[:, 1].min() > -cfg.area_margin_m - 3.0 and loc[:, 1].max() < SURVEY.width_m + cfg.area_margin_m + 3.0


def test_an_unconfirmed_object_is_never_aimed_at():
    cfg = InspectionConfig(enabled=True)
    g = InspectionGuidance.from_config(SURVEY, cfg, LosConfig(), swath_width_m=53.7)
    objects = [Obj(0, np.array([-7.0, 12.0, 4.0])), Obj(5, np.array([-6.0, 20.0, 4.0]), existence_probability=0.5)]
    aimed, _, _ = fly(g, objects)
    assert 5 not in aimed and 0 in aimed


def test_interleaved_breaks_off_and_resumes_coverage():
    cfg = InspectionConfig(enabled=True, mode="interleaved", interleave_radius_m=15.0)
    g = InspectionGuidance.from_config(SURVEY, cfg, LosConfig(), swath_width_m=53.7)
    objects = [Obj(0, np.array([-7.0, 8.0, 4.0]))]
    aimed, path, _ = fly(g, objects)
    events = [e.event for e in g.events]
    assert "break_off" in events and "resume" in events
    assert events.index("break_off") < events.index("resume") < events.index("coverage_done")
    brk = next(e for e in g.events if e.event == "break_off")
    assert brk.object_id == 0 and abs(brk.pos_ne_m[0]) < 2.0, "breaks off on the coverage line, not on the way to it"
    assert aimed == [0]
    assert path[:, 1].max() > 30.0, "coverage resumed to the end of the leg (E 32 m)"


def test_time_budget_ends_the_mission():
    cfg = InspectionConfig(enabled=True, time_budget_s=30.0)
    g = InspectionGuidance.from_config(SURVEY, cfg, LosConfig(), swath_width_m=53.7)
    _, _, t = fly(g, [Obj(0, np.array([-7.0, 12.0, 4.0]))])
    assert g.finished and 30.0 <= t <= 30.2
    assert [e.event for e in g.events][-2:] == ["budget", "done"]


def test_rejoin_path_starts_at_the_nearest_point_of_the_rest():
    path = np.array([[0.0, 0.0], [0.0, 10.0], [-4.0, 10.0], [-4.0, 0.0]])
    np.testing.assert_allclose(rejoin_path(path, (1.0, 6.0)), [[0.0, 6.0], [0.0, 10.0], [-4.0, 10.0], [-4.0, 0.0]])
    np.testing.assert_allclose(rejoin_path(path, (-5.0, 3.0)), [[-4.0, 3.0], [-4.0, 0.0]])
    np.testing.assert_allclose(rejoin_path(path[:1], (3.0, 3.0)), path[:1])
