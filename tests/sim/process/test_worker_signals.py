"""Ctrl-C and the worker processes (:mod:`sim.process.worker_signals`): a worker started under
``sigint_blocked`` holds SIGINT blocked from its first instruction (fork and spawn alike) until
``ignore_sigint``; the sonar pipeline's workers ignore Ctrl-C; a Ctrl-C while the pipeline starts,
or while ``auvsim run`` resets the mission after starting it, leaves no worker or shared memory
block behind."""

from __future__ import annotations

import multiprocessing as mp
import signal
import threading
from multiprocessing.shared_memory import SharedMemory

import pytest

from scenarios import load_scenario
from sim.process import sonar_pipeline
from sim.mission import Mission
from sim.process.sonar_pipeline import SonarPipeline
from sim.process.worker_signals import ignore_sigint, sigint_blocked
from tests.support import PIPELINE_OVERRIDES, pid_alive

pytestmark = pytest.mark.skipif(not hasattr(signal, "pthread_sigmask"), reason="POSIX signal masks")


def _mask() -> set:
    return set(signal.pthread_sigmask(signal.SIG_BLOCK, set()))


def _report_mask(queue) -> None:
    """Child: SIGINT blocked at start? then, after ``ignore_sigint``, blocked? ignored?"""
    at_start = signal.SIGINT in _mask()
    ignore_sigint()
    queue.put((at_start, signal.SIGINT in _mask(), signal.getsignal(signal.SIGINT) == signal.SIG_IGN))


def _sig_ign_bits(pid: int) -> int:
    with open(f"/proc/{pid}/status") as f:
        return int(next(line for line in f if line.startswith("SigIgn:")).split()[1], 16)


@pytest.mark.parametrize("start_method", ["fork", "spawn"])
def test_a_worker_started_under_sigint_blocked_holds_it_until_it_ignores_it(start_method):
    if start_method not in mp.get_all_start_methods():
        pytest.skip(f"no {start_method} start here")
    ctx = mp.get_context(start_method)
    before = _mask()
    queue = ctx.Queue()
    with sigint_blocked():
        assert signal.SIGINT in _mask()
        proc = ctx.Process(target=_report_mask, args=(queue,))
        proc.start()
    assert _mask() == before
    assert queue.get(timeout=60) == (True, False, True)
    proc.join(timeout=30)
    assert proc.exitcode == 0


def test_a_ctrl_c_held_back_by_sigint_blocked_is_raised_when_it_ends():
    reached_end_of_block = False
    with pytest.raises(KeyboardInterrupt):
        with sigint_blocked():
            signal.pthread_kill(threading.get_ident(), signal.SIGINT)  # to this thread, which blocks it
            reached_end_of_block = True
    assert reached_end_of_block


def test_pipeline_workers_ignore_ctrl_c_and_a_ctrl_c_while_it_starts_leaves_nothing(monkeypatch):
    m = Mission(load_scenario("cssn_lawnmower", PIPELINE_OVERRIDES + ["autonomy.atr.detector=classical"]))
    m.reset()
    pipe = SonarPipeline(m.physics, m.fls, m.perception, frames=False)
    try:
        assert all(_sig_ign_bits(pid) & (1 << (signal.SIGINT - 1)) for pid in pipe.pids)
    finally:
        pipe.close()

    rings, procs = [], []
    real_ring, real_dumps, real_start = sonar_pipeline.FrameRing, sonar_pipeline.pickle.dumps, mp.process.BaseProcess.start

    def ring(*a, **kw):
        rings.append(real_ring(*a, **kw))
        return rings[-1]

    def start(self):
        real_start(self)
        procs.append(self)

    def dumps_then_ctrl_c(obj, *a, **kw):  # the second setup: the rings exist, no worker yet
        out = real_dumps(obj, *a, **kw)
        if "atr" in obj:
            raise KeyboardInterrupt
        return out

    monkeypatch.setattr(sonar_pipeline, "FrameRing", ring)
    monkeypatch.setattr(sonar_pipeline.pickle, "dumps", dumps_then_ctrl_c)
    with pytest.raises(KeyboardInterrupt):
        SonarPipeline(m.physics, m.fls, m.perception, frames=True)
    assert len(rings) == 3
    for r in rings:
        with pytest.raises(FileNotFoundError):
            SharedMemory(name=r._shm.name)
    monkeypatch.setattr(sonar_pipeline.pickle, "dumps", real_dumps)

    def send_then_ctrl_c(self, buf, *a, **kw):  # the workers started, their setups on the way
        raise KeyboardInterrupt

    rings.clear()
    monkeypatch.setattr(mp.process.BaseProcess, "start", start)
    monkeypatch.setattr(mp.connection.Connection, "send_bytes", send_then_ctrl_c)
    with pytest.raises(KeyboardInterrupt):
        SonarPipeline(m.physics, m.fls, m.perception, frames=False)
    monkeypatch.undo()
    assert len(procs) == 2 and len(rings) == 2
    assert not any(pid_alive(p.pid) for p in procs)
    for r in rings:
        with pytest.raises(FileNotFoundError):
            SharedMemory(name=r._shm.name)


def test_auvsim_run_stops_the_workers_on_a_ctrl_c_during_the_reset(tmp_path, monkeypatch):
    from sim.mission import run as mission_outputs
    pids = []
    real_reset = Mission.reset

    def reset_then_ctrl_c(self):
        real_reset(self)
        pids.extend(self.worker_pids)
        raise KeyboardInterrupt  # as if Ctrl-C came while the observers start (the recording)

    monkeypatch.setattr(Mission, "reset", reset_then_ctrl_c)
    scn = load_scenario("cssn_lawnmower", PIPELINE_OVERRIDES + ["autonomy.atr.detector=classical"])
    with pytest.raises(KeyboardInterrupt):
        mission_outputs.run_mission(scn, tmp_path / "run", rerun=False, progress=False, workers=2)
    assert len(pids) == 2 and not any(pid_alive(p) for p in pids)
