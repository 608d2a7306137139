"""The mission's sonar computes its objects' ground truth only when an observer reads it
(``sonar_truth``), in the serial and the pipelined loop, and the frames are the same bytes
either way."""

from __future__ import annotations

import pytest

from scenarios import load_scenario
from sim.evaluation.detection_scoring import DetectionScorer
from sim.mission import Mission
from sim.outputs.trajectory_log import TrajectoryLog
from sim.events.records import ObserverBase, PerceptionResult
from sim.sensors.fls import FlsRender

# Dived 10 m short of OPI1 heading for it, survey started at once: frames with targets from t = 0.
OVER = ["autonomy.guidance.mission.start_delay_s=0", "vehicle.initial_pos_ned=[0.0,0.0,2.0]", "duration_s=2.0",
        "autonomy.atr.detector=classical"]


class _Unknown(ObserverBase):
    """Keeps the sonar's renders and the perception results; a user's observer that says
    nothing about the truth (so it may read it)."""

    def __init__(self) -> None:
        self.renders: list[FlsRender] = []
        self.results: list[PerceptionResult] = []

    def on_start(self, info) -> None:
        self.renders.clear()
        self.results.clear()

    def on_step(self, rec) -> None:
        pass

    def on_message(self, name: str, msg) -> None:
        if isinstance(msg, FlsRender):
            self.renders.append(msg)
        elif isinstance(msg, PerceptionResult):
            self.results.append(msg)

    def on_end(self, summary) -> None:
        pass


class _Frames(_Unknown):
    """The same, declaring that it reads no truth but the pose."""

    sonar_truth = False


def _fly(observers, workers: int = 1) -> Mission:
    m = Mission(load_scenario("cssn_lawnmower", OVER), observers=observers, workers=workers)
    try:
        m.reset()
        assert m.pipelined == (workers > 1)
        m.run(progress=False)
    finally:
        m.close()
    return m


def _frame_bytes(obs: _Unknown) -> list[tuple]:
    return [(r.frame.t_s, r.frame.polar.tobytes(), r.frame.fan.tobytes(), r.intensity.tobytes(),
             r.truth.pos_ned.tobytes(), r.truth.R_ns.tobytes()) for r in obs.renders]


def test_truth_is_computed_iff_an_observer_reads_it():
    lean = _Frames()
    m = _fly([TrajectoryLog(), lean])
    assert not m.sonar_truth and not m.fls.render_truth
    assert len(lean.renders) >= 5 and not any(r.truth.objects_computed for r in lean.renders)

    scored, scorer = _Frames(), DetectionScorer("fls", "classical")
    m = _fly([TrajectoryLog(), scored, scorer])
    assert m.sonar_truth and all(r.truth.objects_computed for r in scored.renders)
    assert scorer.metrics()["detections"] > 0 and scorer.n_visible_targets > 0  # scored against real truth
    assert _frame_bytes(scored) == _frame_bytes(lean)
    assert [repr(r.detections) for r in scored.results] == [repr(r.detections) for r in lean.results]

    unknown = _Unknown()  # declares nothing of its own: the base's default, reads the truth
    assert "sonar_truth" not in vars(_Unknown) and unknown.sonar_truth
    m = _fly([TrajectoryLog(), unknown])
    assert m.sonar_truth and all(r.truth.objects_computed for r in unknown.renders)


def test_pipelined_render_worker_skips_the_truth_too():
    serial, piped = _Frames(), _Frames()
    _fly([TrajectoryLog(), serial])
    m = _fly([TrajectoryLog(), piped], workers=2)
    assert not m.sonar_truth
    assert len(piped.renders) >= 5 and not any(r.truth.objects_computed for r in piped.renders)
    assert _frame_bytes(piped) == _frame_bytes(serial)
    with pytest.raises(Exception, match="sonar_truth = True"):
        _ = piped.renders[-1].truth.objects
