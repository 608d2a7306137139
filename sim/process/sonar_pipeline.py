"""Sonar frames and their perception in worker processes while physics and navigation advance.

In the mission loop the forward-looking sonar's frames feed only the perception chain (ATR ->
geolocalisation -> world model), whose results nothing in the loop reads back: guidance flies
the survey plan and the navigation filter fuses no perception result. So frame ``k`` can be
rendered from the scene as it was at its capture, and processed with the navigation estimate
of its delivery time (capture + latency), in other processes, while the mission process steps
on. Processes, not threads: the render and the perception are largely Python and small numpy
operations that hold the GIL, so threads of one process take turns on one core.

Two ``spawn``-started workers (:mod:`sim.process.sonar_workers`): one renders, one runs the ATR
detector (which reads only the frame); the mission process runs the rest of perception
(geolocalisation with the navigation estimate of each frame's delivery, the world model) on
the detections as they come back. That makes three busy processes of similar load, which a
two-core machine's scheduler shares out. The results are the serial loop's bit for bit:

* the render worker holds a copy of the ``MjModel`` with its own ``MjData`` and the sonar
  with its noise generator; at each capture it gets the poses of the geoms on moving bodies
  (what the ray casts read; the static geoms are sent once) and the true vehicle state, and
  renders the frames in capture order, so the noise is drawn in the same order (the sonar
  comes with its ``render_truth``: the objects' ground truth is rendered there only when an
  observer reads it, :class:`sim.mission.Mission`);
* the detection worker holds the mission's detector (rebuilt from its config) and detects on
  each frame as it comes; the mission's own perception then geolocalises the detections and
  updates its world model in delivery order, each frame with the estimate the serial loop
  would pass (kept at its delivery), so the mission's perception holds its state throughout;
* frames go from worker to worker through shared memory (:class:`sim.process.frame_transport.FrameRing`);
  they come back to the mission process only when an observer takes them (an observer sets
  ``sonar_frames = False`` when it ignores the sonar's renders); detections come back the same
  way, and results reach the observers on the mission process, in the serial loop's order,
  once ready;
* :meth:`SonarPipeline.sync` finishes the frames delivered so far and copies the render
  worker's noise generator state into the mission's sonar, so the mission reads the same world
  model and continues the same noise stream as the serial loop.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import pickle
import sys
from collections import deque
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from multiprocessing.connection import wait as wait_any
from typing import Any

import numpy as np

from sim.process.frame_transport import FrameRing, shared_objects
from sim.scene.physics import Physics
from sim.sensors.base import Sensor
from sim.process.sonar_workers import detection_main, render_main
from sim.process.spawn_guard import NO_MAIN_GUARD_EXIT, exit_if_spawn_reimport
from sim.dynamics.truth import VehicleTruth
from sim.process.worker_signals import sigint_blocked

RING_SLOTS = 4  # frames in flight between two processes
CAPTURES_IN_FLIGHT = 2 * RING_SLOTS  # captures sent and not yet rendered before a capture waits
STOP_TIMEOUT_S = 10.0  # wait for a worker to end before terminating it
THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
DETECTIONS_SLOT_BYTES = 1 << 20  # a frame's detections and image-less view (arrays beyond it go in band)


class PipelineError(RuntimeError):
    """A worker process failed (its traceback is in the message) or ended unexpectedly."""


@dataclass(frozen=True)
class FrameTicket:
    """What the scheduler queues in place of a sonar frame being rendered (frame ``k``)."""

    t_s: float
    k: int


@contextmanager
def _one_thread_per_library() -> Iterator[None]:
    """Environment for the workers' start: their BLAS and OpenMP pools get one thread each (the
    pipeline's processes are the parallelism; idle pool threads would spin on the same cores)."""
    saved = {k: os.environ.get(k) for k in THREAD_VARIABLES}
    os.environ.update({k: "1" for k in THREAD_VARIABLES})
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


class SonarPipeline:
    """Renders ``sonar``'s frames and runs ``perception``'s detector on them in two worker
    processes; the rest of ``perception`` runs in this process as the detections come back.

    Args:
        physics: the mission's world (its model is copied to the render worker once; the poses
            of its moving geoms at each capture).
        sonar: the sensor whose frames are pipelined (copied with its noise state).
        perception: the mission's :class:`sim.features.perception.Perception` (its detector is rebuilt
            in the detection worker from ``perception.scenario.autonomy.atr``; the rest runs
            here, on this object, through ``process(render, nav, detections=...)``).
        frames: send each rendered frame back to this process (observers that read them).
        slots: frames in flight in each shared-memory ring.

    The workers start with ``spawn``, which runs the main script again in each worker: a script
    that builds the pipeline (a ``Mission(workers=2)``) outside ``if __name__ == "__main__":``
    would build it again there. Built in a worker starting up, the pipeline ends that worker
    quietly with :data:`NO_MAIN_GUARD_EXIT`, and the mission process raises one
    :class:`PipelineError` saying so.

    Raises:
        ValueError: ``slots`` < 1.
        PipelineError: (from the calls below) a worker failed, ended, or found the main script
            unguarded.
    """

    def __init__(self, physics: Physics, sonar: Sensor, perception: Any, *, frames: bool = True,
                 slots: int = RING_SLOTS) -> None:
        exit_if_spawn_reimport()  # a spawned worker re-running an unguarded script
        if slots < 1:
            raise ValueError(f"SonarPipeline needs slots >= 1, got {slots}")
        self.physics, self.sonar, self.perception = physics, sonar, perception
        self.frames = bool(frames)
        self._procs: list[Any] = []
        self._rings: list[FrameRing] = []
        self._render = self._detect = self._detections_in = self._frames_in = None
        self._n_captured = self._n_rendered = 0
        self._pending: deque[tuple[str, int, Any]] = deque()  # delivered (with their estimate), not yet perceived
        self._perceived: deque[tuple[str, int, Any]] = deque()  # perceived, not yet handed on
        self._detections: dict[int, tuple[Any, Any]] = {}
        self._frames: dict[int, Any] = {}
        self._closed = False
        self._moving = np.flatnonzero(physics.model.geom_bodyid != 0)
        self._static_objects = physics.world.objects
        ctx = mp.get_context("spawn")
        try:
            self._start(ctx, physics, sonar, perception, slots)
        except BaseException:  # a Ctrl-C while starting too: no shared memory block or worker is left
            self.close(sync=False)
            raise

    def _start(self, ctx: Any, physics: Physics, sonar: Sensor, perception: Any, slots: int) -> None:
        """Create the rings and pipes, start the two workers and send them their setups; what
        is made is recorded on ``self`` as it is made, for :meth:`close`."""
        model, data, world = physics.model, physics.data, physics.world
        to_detection, whole = self._frame_bytes(sonar)
        # render -> detection (frames), detection -> mission (detections, the frames' views
        # without images), render -> mission (whole frames, for the observers)
        self._rings.append(FrameRing(ctx, slots, to_detection))
        self._rings.append(FrameRing(ctx, slots, DETECTIONS_SLOT_BYTES))
        if self.frames:
            self._rings.append(FrameRing(ctx, slots, whole))
        self._shared = shared_objects(sonar)
        render_setup = pickle.dumps({
            "sonar": sonar, "model": model, "geom_object_id": world.geom_object_id,
            "geom_reflectivity": world.geom_reflectivity, "vehicle_body_id": world.vehicle_body_id,
            "ray_caster": physics.caster.backend,
            "geom_xpos": data.geom_xpos.copy(), "geom_xmat": data.geom_xmat.copy(), "moving_geoms": self._moving,
            "objects": physics.objects(), "truth_to_perception": getattr(perception, "nav_source", "") == "truth",
        }, protocol=pickle.HIGHEST_PROTOCOL)
        detect_setup = pickle.dumps({"atr": perception.scenario.autonomy.atr, "shared": self._shared},
                                    protocol=pickle.HIGHEST_PROTOCOL)
        self._render, render_end = ctx.Pipe()
        self._detect, detect_end = ctx.Pipe()
        between_r, between_w = ctx.Pipe(duplex=False)
        detections_r, detections_w = ctx.Pipe(duplex=False)
        frames_r, frames_w = ctx.Pipe(duplex=False) if self.frames else (None, None)
        self._detections_in, self._frames_in = detections_r, frames_r
        self._procs = [
            ctx.Process(target=render_main, name="auvsim-sonar-render", daemon=True,
                        args=(render_end, between_w, self._rings[0], frames_w,
                              self._rings[2] if self.frames else None)),
            ctx.Process(target=detection_main, name="auvsim-detection", daemon=True,
                        args=(detect_end, between_r, self._rings[0], detections_w, self._rings[1])),
        ]
        try:
            with _one_thread_per_library(), sigint_blocked():  # the workers ignore it from their start
                for p in self._procs:
                    p.start()
        finally:
            for end in (render_end, detect_end, between_r, between_w, detections_w, frames_w):
                if end is not None:
                    end.close()  # the workers hold them now: their ends close when they end
        # the setups (megabytes) go over the connections, not with the start: spawn writes the
        # start's data to the new process while holding the read end itself, so a worker that
        # ends before reading (an unguarded main script) would leave a large write hanging
        for conn, setup in ((self._render, render_setup), (self._detect, detect_setup)):
            try:
                conn.send_bytes(setup)
            except OSError:
                self._fail(self._why_ended())

    @staticmethod
    def _frame_bytes(sonar: Sensor) -> tuple[int, int]:
        """Slot bytes for the perception's view of a frame (its images; with
        ``nav_source='truth'`` the truth's mask goes in band) and for a whole render (images,
        mask, intensities), with a margin; a sensor without an FLS geometry: 16 MiB each."""
        g = getattr(sonar, "geometry", None)
        if g is None:
            return 16 << 20, 16 << 20
        w, h = g.fan_size_px
        images = g.n_beams * g.n_bins + w * h
        return images + (1 << 16), images + g.n_beams * g.n_bins * (2 + 4 + 4) + (1 << 20)

    # -- the mission loop's calls ------------------------------------------------------------
    def capture(self, truth: VehicleTruth) -> FrameTicket:
        """Start rendering the frame captured now (call where the serial loop would measure,
        after the scene is placed at the present time). Waits, reading the workers' messages,
        while :data:`CAPTURES_IN_FLIGHT` captures are not rendered yet: the mission process then
        never blocks on a full connection while a worker blocks on it (no cycle of full pipes)."""
        self._receive(block=False)
        while self._n_captured - self._n_rendered >= CAPTURES_IN_FLIGHT:
            self._receive(block=True)
        data = self.physics.data
        objects = self.physics.objects()
        k = self._n_captured
        self._send(self._render, ("capture", k, truth, data.geom_xpos[self._moving], data.geom_xmat[self._moving],
                                  None if objects is self._static_objects else objects))
        self._n_captured += 1
        return FrameTicket(truth.t_s, k)

    def deliver(self, name: str, ticket: FrameTicket, nav: Any) -> None:
        """Queue perception of a delivered frame with the estimate ``nav`` of its delivery time."""
        self._pending.append((name, ticket.k, nav))

    def ready(self, wait: bool = False) -> Iterator[tuple[str, Any, Any]]:
        """``(name, frame or None, result)`` of the delivered frames processed so far, in delivery
        order (``wait``: all of them, waiting for the workers); the frame is None unless
        ``frames``. Runs this process's part of perception on the detections that came back.

        Raises:
            PipelineError: a worker failed or ended.
        """
        self._perceive(wait)
        while self._perceived:
            if self.frames and not self._arrived(self._perceived[0][1], self._frames, wait):
                return
            name, k, result = self._perceived.popleft()
            yield name, self._frames.pop(k, None), result

    @property
    def busy(self) -> bool:
        return bool(self._pending or self._perceived)

    def sync(self) -> None:
        """Bring the mission's objects to the state of the serial loop: perception of every
        frame delivered so far (waiting for its detections; the results are handed on by
        :meth:`ready`), the sonar's noise state from the render worker.

        Raises:
            PipelineError: a worker failed or ended.
        """
        self._perceive(wait=True)
        self._send(self._render, ("state",))
        while True:
            for _, msg in self._receive(block=True, want_state=True):
                self.sonar.rng.bit_generator.state = msg[1]
                return

    def close(self, sync: bool = True) -> None:
        """Stop the workers (frames delivered but not yet handed on are dropped); ``sync``
        first copies their state back (:meth:`sync`) when they are sound. Idempotent."""
        if self._closed:
            return
        self._closed = True
        try:
            if sync and self._procs and all(p.is_alive() for p in self._procs):
                self.sync()
        finally:
            for conn in (self._render, self._detect):
                try:
                    if conn is not None:
                        conn.send(("stop",))
                except (OSError, ValueError):
                    pass
            for p in self._procs:
                if p.pid is not None:
                    p.join(STOP_TIMEOUT_S)
                if p.is_alive():
                    p.kill()  # the workers ignore SIGTERM
                    p.join()
            for conn in (self._render, self._detect, self._detections_in, self._frames_in):
                if conn is not None:
                    conn.close()
            for ring in self._rings:
                ring.close()
                ring.unlink()
            self._pending.clear()
            self._perceived.clear()

    @property
    def pids(self) -> list[int]:
        """The worker processes' ids."""
        return [p.pid for p in self._procs]

    # -- internals ---------------------------------------------------------------------------
    def _send(self, conn: Any, msg: tuple) -> None:
        try:
            conn.send(msg)
        except (OSError, ValueError):
            self._fail(self._why_ended())

    def _perceive(self, wait: bool) -> None:
        """Perception (this process's part) of the delivered frames whose detections came back,
        in delivery order (``wait``: of all of them)."""
        while self._pending:
            if not self._arrived(self._pending[0][1], self._detections, wait):
                return
            name, k, nav = self._pending.popleft()
            detections, view = self._detections.pop(k)
            self._perceived.append((name, k, self.perception.process(view, nav, detections=detections)))

    def _arrived(self, k: int, store: dict, wait: bool) -> bool:
        """Whether frame ``k``'s entry is in ``store`` (frames or detections, by frame index)
        after reading what the workers sent (``wait``: reading until it is)."""
        if k not in store:
            self._receive(block=False)
            while wait and k not in store:
                self._receive(block=True)
        return k in store

    def _receive(self, block: bool, want_state: bool = False) -> list[tuple[Any, Any]]:
        """Read what the workers sent (``block``: wait for at least one message); results and
        frames are kept by frame index; ``state`` replies are returned as (connection, message).
        A worker that ended (its process sentinel ready) with nothing left to read fails the
        pipeline."""
        sources = [c for c in (self._render, self._detect, self._detections_in, self._frames_in) if c is not None]
        ended = {p.sentinel: p for p in self._procs}
        states = []
        got = False
        while True:
            ready = wait_any(sources + list(ended), timeout=None if (block and not got) else 0)
            if not ready:
                return states
            for conn in ready:
                if conn in ended:
                    continue
                try:
                    if conn is self._detections_in:
                        k, detections, view = self._rings[1].get(conn, self._shared)
                        self._detections[k] = (detections, view)
                        got = True
                        continue
                    if conn is self._frames_in:
                        k, render = self._rings[2].get(conn, self._shared)
                        self._frames[k] = render
                        got = True
                        continue
                    msg = conn.recv()
                except (EOFError, OSError):
                    self._fail(self._why_ended())
                if msg[0] == "error":
                    self._fail(f"sonar pipeline worker failed:\n{msg[1]}")
                if msg[0] == "rendered":
                    self._n_rendered = msg[1] + 1
                elif msg[0] == "state" and want_state:
                    states.append((conn, msg))
                got = True
            if any(r in ended for r in ready) and not any(c.poll() for c in sources):
                self._fail(self._why_ended())
            if want_state and states:
                return states

    def _why_ended(self) -> str:
        """Why a worker ended without a word: the unguarded main script, or its exit status."""
        for p in self._procs:
            p.join(1.0)
            if p.exitcode == NO_MAIN_GUARD_EXIT:
                main = getattr(sys.modules.get("__main__"), "__file__", None) or "the main script"
                return (f"the sonar workers (workers > 1) start with spawn, which runs {main} again in each "
                        f"worker, and there it builds the mission again: put the code that builds and runs "
                        f"the mission under `if __name__ == \"__main__\":` (or use workers=1)")
        codes = ", ".join(f"{p.name} {p.exitcode}" for p in self._procs if p.exitcode is not None)
        return f"a sonar pipeline worker ended unexpectedly (exit status: {codes or 'unknown'})"

    def _fail(self, why: str) -> None:
        self.close(sync=False)
        raise PipelineError(why) from None
