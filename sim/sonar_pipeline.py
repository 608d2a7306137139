"""Sonar frames and their perception on worker threads while physics and navigation advance.

In the mission loop the forward-looking sonar's frames feed only the perception chain (ATR ->
geolocalisation -> world model), whose results nothing in the loop reads back: guidance flies
the survey plan and the navigation filter fuses no perception result. So frame ``k`` can be
rendered from a copy of the scene taken at its capture time, and processed with the navigation
estimate taken at its delivery time (capture + latency), on other threads, while the main
thread steps on. The results are the serial loop's bit for bit:

* the render sees the capture-time state: ``mujoco.mj_copyData`` of the live ``MjData`` into a
  slot with its own ray caster (casters keep scratch buffers, so a slot is used by one render at
  a time), the true state and the scene objects (immutable snapshots);
* frames are rendered in capture order on one thread, so the sonar's noise generator is drawn
  in the same order; perception runs in delivery order on one thread with the estimate the
  serial loop would have passed;
* observers receive each frame and its perception result in the same order as in the serial
  loop, on the main thread, once they are ready (later relative to the step records; the
  outputs written from step records and from the world model are unchanged).

With two workers a single thread renders and processes (two cores: the main loop and it);
with three or more, rendering and perception get a thread each.
"""

from __future__ import annotations

import queue
from collections import deque
from collections.abc import Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

import mujoco

from sim.physics import Physics
from sim.sensors.base import SceneView, Sensor
from sim.sensors.raycast import MujocoRayCaster
from sim.truth import VehicleTruth


@dataclass(frozen=True)
class FrameTicket:
    """What the scheduler queues in place of a sonar frame being rendered."""

    t_s: float
    frame: Future


class _Slot:
    """A scene copy and a ray caster over it."""

    def __init__(self, physics: Physics) -> None:
        self.data = mujoco.MjData(physics.model)
        w = physics.world
        self.caster = MujocoRayCaster(physics.model, self.data, w.geom_object_id, w.geom_reflectivity,
                                      w.vehicle_body_id)


class SonarPipeline:
    """Renders ``sonar``'s frames and runs ``perception`` on them off the main thread.

    Args:
        physics: the mission's world (its ``MjData`` is copied at each capture).
        sonar: the sensor whose frames are pipelined.
        process: ``(frame, nav) -> result``, the perception of one delivered frame.
        workers: total threads the loop may use, main thread included (>= 2).
        slots: scene copies in flight (a capture waits for a free one).

    Raises:
        ValueError: fewer than 2 workers.
    """

    def __init__(self, physics: Physics, sonar: Sensor, process: Any, workers: int, slots: int = 3) -> None:
        if workers < 2:
            raise ValueError(f"SonarPipeline needs workers >= 2, got {workers}")
        self.physics, self.sonar, self.process = physics, sonar, process
        self._render_pool = ThreadPoolExecutor(1, thread_name_prefix="auvsim-sonar-render")
        self._process_pool = (ThreadPoolExecutor(1, thread_name_prefix="auvsim-perception") if workers >= 3
                              else self._render_pool)
        self._free: queue.SimpleQueue[_Slot] = queue.SimpleQueue()
        for _ in range(max(int(slots), 1)):
            self._free.put(_Slot(physics))
        self._pending: deque[tuple[str, Future]] = deque()

    def capture(self, truth: VehicleTruth) -> FrameTicket:
        """Start rendering the frame captured now (call where the serial loop would measure)."""
        slot = self._free.get()  # waits while every copy is being rendered
        mujoco.mj_copyData(slot.data, self.physics.model, self.physics.data)
        scene = SceneView(self.physics.t_s, slot.caster, self.physics.objects())
        return FrameTicket(truth.t_s, self._render_pool.submit(self._render, slot, truth, scene))

    def _render(self, slot: _Slot, truth: VehicleTruth, scene: SceneView) -> Any:
        try:
            return self.sonar.measure(truth, scene)
        finally:
            self._free.put(slot)

    def deliver(self, name: str, ticket: FrameTicket, nav: Any) -> None:
        """Queue perception of a delivered frame with the estimate ``nav`` of its delivery time."""
        self._pending.append((name, self._process_pool.submit(self._perceive, ticket.frame, nav)))

    def _perceive(self, frame: Future, nav: Any) -> tuple[Any, Any]:
        msg = frame.result()
        return msg, self.process(msg, nav)

    def ready(self, wait: bool = False) -> Iterator[tuple[str, Any, Any]]:
        """``(name, frame, result)`` of the delivered frames processed so far, in delivery order
        (``wait``: all of them, waiting for the workers). Re-raises a worker's exception."""
        while self._pending and (wait or self._pending[0][1].done()):
            name, fut = self._pending.popleft()
            msg, result = fut.result()
            yield name, msg, result

    @property
    def busy(self) -> bool:
        return bool(self._pending)

    def close(self) -> None:
        """Stop the threads (frames not yet delivered are dropped)."""
        self._render_pool.shutdown(wait=True, cancel_futures=True)
        if self._process_pool is not self._render_pool:
            self._process_pool.shutdown(wait=True, cancel_futures=True)
        self._pending.clear()
