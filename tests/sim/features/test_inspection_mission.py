"""Active inspection end to end: a short mission whose world model sends the vehicle to look
again at a target it saw only from afar, and the look shrinks that target's ellipse."""

from __future__ import annotations

import pytest

from scenarios import load_scenario
from scenarios.load import ScenarioError
from sim.events.records import ObserverBase
from sim.features import InspectionFeature
from sim.events.records import InspectionGoal
from sim.mission import Mission
from sim.mission.parts import build_mission_parts
from sim.scene.physics import Physics

# cssn_inspect's world cut to two OPIs beside a 16 m coverage leg: OPI4 8 m to starboard is seen
# from the centre line at long range only
SHORT = ["world.targets=[{name: OPI1, shape: half_sphere, pos_ned: [0.0, 10.0, 4.0], radius_m: 0.5}, "
         "{name: OPI4, shape: half_sphere, pos_ned: [-8.0, 10.0, 4.0], radius_m: 0.5}]",
         "autonomy.guidance.survey.length_m=16.0", "duration_s=400"]


class Goals(ObserverBase):
    def __init__(self) -> None:
        self.goals: list[InspectionGoal] = []
        self.modes: set[str] = set()

    def on_start(self, info): pass
    def on_end(self, summary): pass

    def on_step(self, record):
        self.modes.add(record.mode)

    def on_message(self, name, msg):
        if isinstance(msg, InspectionGoal):
            self.goals.append(msg)


@pytest.fixture(scope="module")
def flown():
    scenario = load_scenario("cssn_inspect", SHORT)
    goals = Goals()
    mission = Mission(scenario, nav_source="truth", observers=[goals])
    summary = mission.run(progress=False)
    feature = mission.feature(InspectionFeature)
    metrics: dict = {}
    feature.add_metrics(metrics, None)
    yield summary, metrics["inspection"], goals, mission.perception.world_model_metrics()
    mission.close()


def test_a_target_seen_from_afar_is_inspected_and_its_look_ellipse_shrinks(flown):
    summary, ins, seen, wm = flown
    goals = seen.goals
    assert {"survey", "inspect", "surface"} <= seen.modes  # the step records' mode names the leg
    assert ins["legs_started"] >= 1 and ins["legs_sent"] == ins["legs_completed"] + ins["legs_ended_early"]
    assert summary.finished and not summary.aborted
    assert wm["matched"] == 2 and wm["false"] == 0
    assert ins["legs"], "OPI4, seen from the centre line only, is sent a leg"
    for leg in ins["legs"]:  # flown to its end, or ended early once the looks on the way made it confident
        assert leg["outcome"] in ("completed", "ended early: object confident"), leg
        assert leg["look_2sigma_after_m"] < leg["look_2sigma_before_m"] * 0.9
        assert leg["t_end_s"] > leg["t_assigned_s"]
    assert ins["legs_at_false_objects"] == 0
    assert ins["end_reason"] == "all confident" and ins["time_to_confident_map_s"] is not None
    assert all(o["confident"] for o in ins["objects"] if o["confirmed"])
    # the recording's goals: coverage first, a leg aimed at an object, done last
    assert goals[0].phase == "coverage" and goals[-1].phase == "done"
    assert any(g.phase == "inspect" and g.object_id is not None and g.start_ne_m is not None for g in goals)


def test_the_lawnmower_stays_the_default():
    scenario = load_scenario("cssn_lawnmower")
    assert not scenario.autonomy.guidance.inspection.enabled
    parts = build_mission_parts(scenario, Physics(scenario), 0)
    assert type(parts.guidance).__name__ == "SurveyGuidance"


@pytest.mark.parametrize("override, says", [
    ("autonomy.atr.detector=none", "needs an enabled forward-looking sonar"),
    ("sensors.fls.enabled=false", "needs an enabled forward-looking sonar"),
    ("autonomy.guidance.buddy.enabled=true", "cannot fly with autonomy.tracking or buddy"),
])
def test_inspection_without_its_world_model_is_refused_at_load(override, says):
    with pytest.raises(ScenarioError, match=says):
        load_scenario("cssn_inspect", [override])
