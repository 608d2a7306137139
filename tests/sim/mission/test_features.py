"""The mission loop's feature protocol: a study of the caller's own plugs in without touching
the loop, is called at the declared points in the declared order, and the shipped studies are
built exactly where their config asks for them."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from autonomy.control.setpoint import Setpoint
from autonomy.messages import DvlMsg
from scenarios import load_scenario
from sim.features import (FEATURES, McmFullFeature, MsisLocalizationFeature, SeaTrialFeature, SurveyPerceptionFeature,
                          TrackingFeature)
from sim.mission import Mission
from sim.features.base import MissionFeature
from sim.events.scheduler import AUTONOMY

ROOT = Path(__file__).resolve().parents[3]
QUIET = ["autonomy.atr.detector=none", "duration_s=3"]


class _Recorder(MissionFeature):
    """Records every hook call; processes the depth sensor's messages; counts DVL messages."""

    name = "recorder"
    calls: list[tuple[str, float]] = []

    def __init__(self, ctx) -> None:
        self.ctx = ctx
        self.depth_results: list[float] = []
        self.dvl_seen = 0

    @classmethod
    def build(cls, ctx):
        return cls(ctx)

    def reset(self, ports) -> None:
        self.ports = ports
        self.calls.clear()
        self.calls.append(("reset", ports.t_s))
        ports.on_message(DvlMsg, self._on_dvl)
        ports.process_source("depth", self._on_depth)

    def _on_dvl(self, msg) -> None:
        self.dvl_seen += 1

    def _on_depth(self, msg, nav) -> None:
        self.depth_results.append(float(msg.depth_m))
        return None

    def start(self, truth, nav) -> None:
        self.calls.append(("start", truth.t_s))

    def after_physics(self, t_s, truth) -> None:
        self.calls.append(("after_physics", t_s))

    def before_nav(self, t_s, truth) -> None:
        self.calls.append(("before_nav", t_s))

    def after_nav(self, t_s, nav) -> None:
        self.calls.append(("after_nav", t_s))

    def end_of_step(self) -> None:
        self.calls.append(("end_of_step", self.ports.t_s))

    def finish(self, t_s) -> None:
        self.calls.append(("finish", t_s))


class _Driver(MissionFeature):
    """Drives the vehicle: a fixed heading and speed at a fixed depth."""

    name = "driver"
    drives_guidance = True
    n_setpoints = 0

    @classmethod
    def build(cls, ctx):
        return cls()

    def setpoint(self, t_s, nav):
        type(self).n_setpoints += 1
        return Setpoint(speed_mps=0.8, heading_rad=np.pi / 2, depth_m=2.0)


def test_a_feature_of_ones_own_is_called_at_each_declared_point_in_order():
    m = Mission(load_scenario("cssn_lawnmower", QUIET), perception=False, features=[_Recorder])
    rec = m.feature(_Recorder)
    assert rec is not None and m.features[-1] is rec
    m.run(progress=False)
    calls = _Recorder.calls
    assert calls[0] == ("reset", 0.0) and calls[1] == ("start", 0.0) and calls[-1][0] == "finish"
    per_step = [c for c in calls[2:-1]]
    assert len(per_step) == 4 * round(3.0 / m.autonomy_dt_s)
    for k in range(0, len(per_step), 4):
        names = [c[0] for c in per_step[k:k + 4]]
        assert names == ["after_physics", "before_nav", "after_nav", "end_of_step"], names
        assert len({c[1] for c in per_step[k:k + 4]}) == 1  # all at the step's time
    # its registered handlers got the messages: every depth reading, every DVL message
    delivered = m.summary().messages_delivered
    assert len(rec.depth_results) == delivered["depth"] > 0
    assert rec.dvl_seen == delivered["dvl"] > 0


class _Ticker(_Recorder):
    """Declares one periodic event in each phase of the loop's clock."""

    name = "ticker"

    def reset(self, ports) -> None:
        super().reset(ports)
        ports.every("ticker/physics", 2.0, lambda truth: self.calls.append(("physics_event", truth.t_s)),
                    stage="ticker")
        ports.every("ticker/autonomy", ports.autonomy_rate_hz,
                    lambda truth: self.calls.append(("autonomy_event", truth.t_s)), stage="ticker", phase=AUTONOMY)


def test_declared_events_fire_in_their_phase_of_the_period():
    m = Mission(load_scenario("cssn_lawnmower", QUIET), perception=False, features=[_Ticker])
    m.run(progress=False)
    calls = _Ticker.calls
    # the physics-phase event fires at t = 0 (reset) and every 0.5 s, within the physics substeps
    assert [t for n, t in calls if n == "physics_event"] == pytest.approx([0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0])
    assert calls.index(("physics_event", 0.0)) < calls.index(("start", 0.0))
    # the autonomy-phase event: once a period from the first period on, after the features'
    # before_nav, before the navigation filter (after_nav)
    per_step = [c for c in calls if c[0] != "physics_event"][2:-1]
    assert len(per_step) == 5 * round(3.0 / m.autonomy_dt_s)
    for k in range(0, len(per_step), 5):
        names = [c[0] for c in per_step[k:k + 5]]
        assert names == ["after_physics", "before_nav", "autonomy_event", "after_nav", "end_of_step"], names


def test_the_feature_that_drives_the_guidance_replaces_the_survey_state_machine():
    _Driver.n_setpoints = 0
    m = Mission(load_scenario("cssn_lawnmower", ["autonomy.atr.detector=none", "duration_s=20"]), perception=False,
                features=[_Driver])
    m.run(progress=False)
    assert _Driver.n_setpoints == round(20.0 / m.autonomy_dt_s)
    assert m.fsm.mode == "idle"  # never updated
    truth = m.physics.truth()
    assert abs(truth.rpy_rad[2] - np.pi / 2) < 0.2 and truth.pos_ned[1] > 3.0  # heading east, moved east


def test_two_features_driving_the_guidance_are_refused():
    class _Other(_Driver):
        name = "other"

    with pytest.raises(ValueError, match="more than one feature drives the guidance"):
        Mission(load_scenario("cssn_lawnmower", QUIET), perception=False, features=[_Driver, _Other])


@pytest.mark.parametrize("scenario, overrides, expected", [
    ("cssn_lawnmower", [], {SurveyPerceptionFeature}),
    ("cssn_sea_trial", [], {SurveyPerceptionFeature, SeaTrialFeature}),
    ("pool_circular", [], {MsisLocalizationFeature}),
    ("track_static_vehicle", [], {TrackingFeature}),
    ("diver_follow", [], {TrackingFeature}),
    ("mcm_survey_full", [], {McmFullFeature}),
])
def test_each_shipped_study_is_built_where_its_config_asks_for_it(scenario, overrides, expected):
    m = Mission(load_scenario(scenario, overrides))
    assert {type(f) for f in m.features} == expected
    driver = [f for f in m.features if f.drives_guidance]
    assert bool(driver) == load_scenario(scenario, overrides).autonomy.guidance.buddy.enabled


def test_no_perception_feature_without_perception():
    m = Mission(load_scenario("cssn_lawnmower", QUIET), perception=False)
    assert m.features == () and m.perception is None


def test_the_loop_names_no_study():
    """The loop module imports no study's code and its step names none: studies live in
    sim/features/ (the loop reaches them only through the protocol)."""
    src = (ROOT / "sim" / "mission" / "loop.py").read_text()
    tree = ast.parse(src)
    imported = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    studies = ("autonomy.tracking", "autonomy.guidance.buddy", "sim.comms", "sim.features.surface_runner", "autonomy.msis",
               "sim.mcm", "sim.process.sonar_pipeline", "autonomy.navigation.delayed", "sim.features.perception")
    assert not [m for m in imported if m and m.startswith(studies)]
    step = next(n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef) and n.name == "step")
    body = ast.get_source_segment(src, step)
    for word in ("tracking", "link", "buddy", "msis", "mcm", "surface", "pipeline"):
        assert word not in body.lower(), word
    assert step.end_lineno - step.lineno < 50


def test_every_feature_declares_its_name_and_build():
    for cls in FEATURES:
        assert cls.name != MissionFeature.name
        assert cls.build.__func__ is not MissionFeature.build.__func__
    assert len({cls.name for cls in FEATURES}) == len(FEATURES)


class _Written(MissionFeature):
    """Adds a metric and writes a file of its own into a run folder."""

    name = "written"

    @classmethod
    def build(cls, ctx):
        return cls()

    def reset(self, ports) -> None:
        self.n_steps = 0

    def after_nav(self, t_s, nav) -> None:
        self.n_steps += 1

    def add_metrics(self, metrics, log) -> None:
        metrics["written"] = {"steps": self.n_steps}

    def write_outputs(self, out_dir, metrics, title) -> None:
        (out_dir / "written.txt").write_text(f"{self.n_steps}\n")


def test_run_mission_writes_a_feature_of_ones_own(tmp_path):
    import json

    from sim.mission.run import run_mission

    metrics = run_mission(load_scenario("cssn_lawnmower", QUIET), tmp_path / "run", rerun=False, progress=False,
                          features=[_Written])
    steps = round(3.0 / 0.1)  # 10 Hz autonomy
    assert metrics["written"] == {"steps": steps}
    assert json.loads((tmp_path / "run" / "metrics.json").read_text())["written"] == {"steps": steps}
    assert (tmp_path / "run" / "written.txt").read_text() == f"{steps}\n"


def test_the_architecture_docs_example_runs():
    src = (ROOT / "docs" / "architecture.md").read_text()
    code = src.split("A minimal one:\n\n```python\n", 1)[1].split("```", 1)[0]
    code = code.replace('"duration_s=60"', '"duration_s=3", "autonomy.atr.detector=none"')
    scope: dict = {"__name__": "docs_example"}
    exec(compile(code, "docs/architecture.md", "exec"), scope)
    m = scope["m"]
    feature = m.feature(scope["DepthLog"])
    assert feature.n_dvl == m.summary().messages_delivered["dvl"] > 0 and len(feature.depth_m) == 30


def test_an_instance_or_a_name_is_refused_with_what_is_expected():
    with pytest.raises(TypeError, match="MissionFeature subclasses"):
        Mission(load_scenario("cssn_lawnmower", QUIET), features=[_Written()])
    with pytest.raises(TypeError, match="scenarios.load_scenario"):
        Mission("cssn_lawnmower")
    with pytest.raises(NotImplementedError, match="return the feature for this mission"):
        class _NoBuild(MissionFeature):
            name = "no_build"
        Mission(load_scenario("cssn_lawnmower", QUIET), features=[_NoBuild])
