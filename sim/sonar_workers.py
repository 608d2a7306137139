"""The two worker processes of :mod:`sim.sonar_pipeline`: sonar rendering and perception.

Each runs a loop over messages from the mission process (``multiprocessing`` connections,
``spawn`` start) and ends on ``("stop",)`` or when the mission process's end of its connection
closes (the mission process died), so none outlives it. Both ignore SIGINT and SIGTERM: Ctrl-C
(or a SIGTERM sent to the whole process group) reaches the mission process, which stops them
after handing on what is finished; a killed mission process ends them through the closed
connection (or, for a writer waiting on a full ring, :meth:`FrameRing.put`'s parent check). A worker's exception is
sent to the mission process as ``("error", traceback text)``, then the worker ends.

Render worker (:func:`render_main`): holds its own ``MjData`` over a copy of the mission's
``MjModel`` and the sonar with its noise generator. Messages in:
``("capture", k, truth, xpos, xmat, objects)`` (the poses of the geoms on moving bodies and,
when objects move, the scene objects, at capture), ``("state",)``, ``("stop",)``. It renders
frame ``k`` exactly as the serial loop (same geom poses, same draws in the same order), sends
the perception's view of it (the frame; with ``nav_source='truth'`` also its truth) to the
perception worker, and, when the mission's observers take frames, ``(k, render)`` to the
mission process over a connection of its own, both through shared memory (:class:`sim.frame_transport.FrameRing`).
``("rendered", k)`` then tells the mission process it is done with capture ``k`` (which bounds the
captures in flight); ``("state",)`` answers ``("state", noise generator state)``.

Perception worker (:func:`perception_main`): holds the mission's
:class:`sim.perception.Perception` (its detector rebuilt from the ATR config). Messages in:
``("nav", k, nav)`` at frame ``k``'s delivery, ``("state",)``, ``("stop",)``; frames from the
render worker. Handled strictly in order (a ``nav`` waits for its frame): frame ``k`` is
processed with ``nav`` and ``("result", k, result)`` sent back; ``("state",)`` answers
``("state", pmha, n_frames)``, the perception's state after every frame delivered before it.
"""

from __future__ import annotations

import pickle
import signal
import traceback
from collections import deque
from multiprocessing.connection import wait
from typing import Any

from sim.frame_transport import FrameRing, shared_objects


def _worker_start() -> None:
    """Ignore Ctrl-C and SIGTERM (the mission process stops the worker) and keep OpenCV to one thread."""
    import cv2

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    cv2.setNumThreads(1)


def _report(conn: Any) -> None:
    try:
        conn.send(("error", traceback.format_exc()))
    except (OSError, EOFError):
        pass


def render_main(conn: Any, to_perception: Any, ring_perception: FrameRing, to_main: Any,
                ring_main: FrameRing | None) -> None:
    """Render-worker loop (see the module doc); frames for the mission's observers go over
    ``to_main`` through ``ring_main`` (None: not wanted). The first message on ``conn`` is the
    setup (bytes, sent after the start so that the start's own pipe write stays small): the
    pickled dict ``sonar``, ``model``,
    ``geom_object_id``, ``geom_reflectivity``, ``vehicle_body_id``, ``geom_xpos``, ``geom_xmat``,
    ``moving_geoms``, ``objects``, ``truth_to_perception``."""
    _worker_start()
    try:
        import dataclasses

        import mujoco

        from sim.sensors.base import SceneView
        from sim.sensors.raycast import MujocoRayCaster

        s = pickle.loads(conn.recv_bytes())
        sonar, model, moving = s["sonar"], s["model"], s["moving_geoms"]
        data = mujoco.MjData(model)
        data.geom_xpos[:], data.geom_xmat[:] = s["geom_xpos"], s["geom_xmat"]
        caster = MujocoRayCaster(model, data, s["geom_object_id"], s["geom_reflectivity"], s["vehicle_body_id"])
        objects, with_truth = s["objects"], s["truth_to_perception"]
        shared_ids = {id(v): name for name, v in shared_objects(sonar).items()}
        while True:
            try:
                msg = conn.recv()
            except EOFError:
                return
            if msg[0] == "stop":
                return
            if msg[0] == "state":
                conn.send(("state", sonar.rng.bit_generator.state))
                continue
            _, k, truth, xpos, xmat, moved = msg
            data.geom_xpos[moving], data.geom_xmat[moving] = xpos, xmat
            if moved is not None:
                objects = moved
            render = sonar.measure(truth, SceneView(truth.t_s, caster, objects))
            # the perception's view: the frame (and the truth where it navigates by it), no images
            view = dataclasses.replace(render, **{f.name: None for f in dataclasses.fields(render)
                                                  if f.name != "frame" and not (with_truth and f.name == "truth")})
            ring_perception.put(to_perception, (k, view), shared_ids)
            if ring_main is not None:
                ring_main.put(to_main, (k, render), shared_ids)
            conn.send(("rendered", k))
    except BaseException:
        _report(conn)
    finally:
        ring_perception.close()
        if ring_main is not None:
            ring_main.close()


def perception_main(conn: Any, from_render: Any, ring: FrameRing) -> None:
    """Perception-worker loop (see the module doc). The first message on ``conn`` (bytes): the mission's ``Perception``
    pickled with its detector as the persistent id ``"detector"`` (rebuilt here from
    ``perception.scenario.autonomy.atr``)."""
    _worker_start()
    try:
        import io

        from autonomy.atr import build_detector

        class _Loader(pickle.Unpickler):
            def persistent_load(self, pid: Any) -> Any:
                return None  # the detector, rebuilt below

        perception = _Loader(io.BytesIO(conn.recv_bytes())).load()
        perception.detector = build_detector(perception.scenario.autonomy.atr)
        shared = shared_objects(perception.fls)
        frames: dict[int, Any] = {}
        todo: deque[tuple] = deque()
        sources = [conn, from_render]
        while sources:
            for src in wait(sources):
                try:
                    if src is from_render:
                        k, view = ring.get(from_render, shared)
                        frames[k] = view
                    else:
                        todo.append(conn.recv())
                except EOFError:
                    if src is conn:
                        return
                    sources.remove(src)  # the render worker ended (its error went to the mission)
            while todo:
                msg = todo[0]
                if msg[0] == "stop":
                    return
                if msg[0] == "state":
                    conn.send(("state", perception.pmha, perception.n_frames))
                elif msg[1] in frames:
                    conn.send(("result", msg[1], perception.process(frames.pop(msg[1]), msg[2])))
                else:
                    break  # this nav's frame is still being rendered
                todo.popleft()
    except BaseException:
        _report(conn)
    finally:
        ring.close()
