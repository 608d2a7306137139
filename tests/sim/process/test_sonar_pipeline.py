"""Pipelined sonar and perception (``workers`` > 1, worker processes) against the serial loop:
the same bytes, no process left behind, a worker's failure reported."""

from __future__ import annotations

import copy
import dataclasses
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from scenarios import load_scenario
from sim.evaluation.detection_scoring import DetectionScorer
from sim.features import SurveyPerceptionFeature
from sim.mission import Mission
from sim.outputs.trajectory_log import TrajectoryLog
from sim.features.perception import Perception
from sim.events.records import ObserverBase, PerceptionResult
from sim.sensors.fls import FlsRender, FlsSensor
from sim.process.sonar_pipeline import PipelineError, SonarPipeline
from tests.support import PIPELINE_OVERRIDES, pid_alive

# Dived 10 m short of OPI1 heading for it, survey started at once: frames with targets from t = 0.
ROOT = Path(__file__).resolve().parents[3]


class _Messages(ObserverBase):
    def __init__(self) -> None:
        self.seen: list[tuple] = []

    def on_start(self, info) -> None:
        self.seen.clear()

    def on_step(self, rec) -> None:
        pass

    def on_message(self, name: str, msg) -> None:
        if isinstance(msg, FlsRender):
            self.seen.append((name, "frame", msg.frame.t_s, msg.frame.polar.tobytes() + msg.frame.fan.tobytes(),
                              msg.intensity.tobytes(), msg.truth.mask_polar.tobytes(), repr(msg.truth.objects)))
        elif isinstance(msg, PerceptionResult):
            self.seen.append((name, "result", msg.t_s, repr(msg.detections), repr(msg.localized)))

    def on_end(self, summary) -> None:
        pass


def _run(workers: int, tmp_path, detector: str, frames: bool = True):
    log, msgs, scorer = TrajectoryLog(), _Messages(), DetectionScorer("fls", detector)
    m = Mission(load_scenario("cssn_lawnmower", PIPELINE_OVERRIDES + [f"autonomy.atr.detector={detector}"]),
                observers=[log, msgs, scorer] if frames else [log], workers=workers)
    m.reset()
    pids = m.worker_pids
    assert (workers > 1) == bool(pids) and all(pid_alive(p) for p in pids)
    summary = m.run(progress=False)
    m.close()
    assert not any(pid_alive(p) for p in pids)  # no worker left behind
    path = tmp_path / f"trajectory_{workers}.csv"
    log.write_csv(path)
    return (path.read_bytes(), json.dumps(m.perception.world_model_json()), msgs.seen, summary, scorer.metrics(),
            m.fls.rng.bit_generator.state)


@pytest.mark.parametrize(("detector", "workers"), [("cnn", 2), ("classical", 3)])
def test_pipelined_loop_gives_the_serial_outputs(tmp_path, detector, workers):
    csv1, wm1, seen1, s1, score1, rng1 = _run(1, tmp_path, detector)
    frames = [s for s in seen1 if s[1] == "frame"]
    assert len(frames) >= 8  # 3 Hz over 3 s
    assert json.loads(wm1)["objects"]  # something was detected and fused into the world model
    csv_w, wm_w, seen_w, s_w, score_w, rng_w = _run(workers, tmp_path, detector)
    assert csv_w == csv1
    assert wm_w == wm1
    assert seen_w == seen1  # every frame and result reached the observers, in order
    assert s_w.messages_delivered == s1.messages_delivered
    assert score1["detections"] > 0 and score_w == score1  # the observer scoring detections saw the same
    assert rng_w == rng1  # the sonar's noise stream carries on where the render worker left it


def test_frames_stay_in_the_workers_when_no_observer_takes_them(tmp_path):
    csv1, wm1, *_ = _run(1, tmp_path, "classical", frames=False)
    m = Mission(load_scenario("cssn_lawnmower", PIPELINE_OVERRIDES + ["autonomy.atr.detector=classical"]),
                observers=[TrajectoryLog()], workers=2)
    m.reset()
    assert m.feature(SurveyPerceptionFeature).pipeline.frames is False
    m.close()
    csv2, wm2, *_ = _run(2, tmp_path, "classical", frames=False)
    assert csv2 == csv1 and wm2 == wm1
    assert json.loads(wm1)["objects"]


def test_pipeline_is_off_where_perception_feeds_back_or_is_absent():
    scn = load_scenario("cssn_lawnmower", PIPELINE_OVERRIDES + ["sensors.fls.enabled=false"])
    m = Mission(scn, workers=2)
    m.reset()
    assert not m.pipelined
    with pytest.raises(ValueError, match="workers"):
        Mission(scn, workers=0)


def test_perception_on_detections_made_elsewhere_equals_perception_on_the_frame():
    # the pipeline detects on a worker and runs the rest of perception on an image-less view
    m = Mission(load_scenario("cssn_lawnmower", PIPELINE_OVERRIDES + ["autonomy.atr.detector=classical"]))
    m.reset()
    whole = Perception(m.scenario, m.fls, m.physics.world.seabed, m.parts.waypoints_ne)
    split = Perception(m.scenario, m.fls, m.physics.world.seabed, m.parts.waypoints_ne)
    n_detections = 0
    for _ in range(6):
        for _ in range(67):
            m.physics.step(np.zeros(m.physics.params.n_thrusters))
        render = m.fls.measure(m.physics.truth(), m.physics.scene())
        nav = m.nav_filter.estimate()
        detections = split.detector.detect(render.frame)
        n_detections += len(detections)
        view = dataclasses.replace(render, frame=dataclasses.replace(render.frame, polar=None, fan=None),
                                   truth=None, mean_intensity=None, intensity=None)
        a, b = whole.process(render, nav), split.process(view, nav, detections=detections)
        assert repr(a) == repr(b)
    assert n_detections > 0 and whole.n_frames == split.n_frames == 6
    assert json.dumps(whole.world_model_json()) == json.dumps(split.world_model_json())
    assert whole.world_model_json()["objects"]


def _feed(m: Mission, pipe: SonarPipeline) -> None:
    """Three frames through ``pipe``, 0.2 s apart, and wait for their results."""
    for _ in range(3):
        for _ in range(40):
            m.physics.step(np.zeros(m.physics.params.n_thrusters))
        pipe.deliver("fls", pipe.capture(m.physics.truth()), m.nav_filter.estimate())
    list(pipe.ready(wait=True))


class _FailingFls(FlsSensor):
    """A sonar whose render fails on its second frame (in the render worker)."""

    def measure(self, truth, scene):
        self.n_rendered = getattr(self, "n_rendered", 0) + 1
        if self.n_rendered >= 2:
            raise RuntimeError("render failed on purpose")
        return super().measure(truth, scene)


def test_a_worker_failure_is_raised_with_its_traceback_and_ends_the_workers():
    m = Mission(load_scenario("cssn_lawnmower", PIPELINE_OVERRIDES + ["autonomy.atr.detector=classical"]))
    m.reset()
    failing = copy.copy(m.fls)
    failing.__class__ = _FailingFls
    pipe = SonarPipeline(m.physics, failing, m.perception, frames=False)
    pids = pipe.pids
    with pytest.raises(PipelineError, match="render failed on purpose"):
        _feed(m, pipe)
    assert not any(pid_alive(pid) for pid in pids)
    pipe.close()  # already closed: nothing more to do


def test_a_killed_worker_is_reported():
    m = Mission(load_scenario("cssn_lawnmower", PIPELINE_OVERRIDES + ["autonomy.atr.detector=classical"]))
    m.reset()
    pipe = SonarPipeline(m.physics, m.fls, m.perception, frames=False)
    os.kill(pipe.pids[1], signal.SIGKILL)  # the detection worker
    with pytest.raises(PipelineError, match="ended unexpectedly.*auvsim-detection -9"):
        _feed(m, pipe)
    assert not any(pid_alive(pid) for pid in pipe.pids)


UNGUARDED = """
from scenarios import load_scenario
from sim.mission import Mission
Mission(load_scenario("cssn_lawnmower", {over!r}), workers=2).run(progress=False)
"""


def test_a_script_without_the_main_guard_gets_one_clear_error_not_a_hang(tmp_path):
    # spawn runs the script again in each worker, which would build the mission there again
    script = tmp_path / "unguarded.py"
    script.write_text(UNGUARDED.format(over=PIPELINE_OVERRIDES + ["autonomy.atr.detector=classical"]))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120, env=env,
                          cwd=tmp_path)
    assert proc.returncode == 1
    assert proc.stderr.count("Traceback") == 1  # the mission process's, none from the workers
    assert 'PipelineError: the sonar workers' in proc.stderr and 'if __name__ == "__main__":' in proc.stderr
    assert str(script) in proc.stderr
    assert "leaked" not in proc.stderr  # shared memory and semaphores released


def test_a_killed_mission_process_leaves_no_worker_behind():
    # the render worker may be waiting for a ring slot that only the mission process frees
    code = ("import os, sys, time\nfrom scenarios import load_scenario\nfrom sim.mission import Mission\n"
            "if __name__ == '__main__':\n"
            f"    m = Mission(load_scenario('cssn_lawnmower', {PIPELINE_OVERRIDES[:-1] + ['duration_s=600']!r}), workers=2)\n"
            "    m.reset()\n    print(*m.worker_pids, flush=True)\n"
            "    for _ in range(3000):\n        m.step()\n")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True, env=env)
    pids = [int(p) for p in proc.stdout.readline().split()]
    assert len(pids) == 2
    time.sleep(3.0)  # frames in flight, rings filling
    proc.kill()
    proc.wait()
    deadline = time.monotonic() + 15.0
    while any(pid_alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not any(pid_alive(p) for p in pids)
