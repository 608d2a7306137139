"""The two worker processes of :mod:`sim.process.sonar_pipeline`: sonar rendering and ATR detection.

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
detection worker, and, when the mission's observers take frames, ``(k, render)`` to the
mission process over a connection of its own, both through shared memory (:class:`sim.process.frame_transport.FrameRing`).
``("rendered", k)`` then tells the mission process it is done with capture ``k`` (which bounds the
captures in flight); ``("state",)`` answers ``("state", noise generator state)``.

Detection worker (:func:`detection_main`): holds the mission's ATR detector (rebuilt from its
config; it reads only the frame, not the navigation). Messages in: ``("stop",)``; frames from
the render worker, in capture order. For frame ``k`` it runs the detector and sends ``(k,
detections, the frame's view without its images)`` to the mission process through shared
memory, where the rest of perception (geolocalisation with the estimate of the frame's
delivery, the world model) runs in delivery order.
"""

from __future__ import annotations

import pickle
import signal
import traceback
from multiprocessing.connection import wait
from typing import Any

from sim.process.frame_transport import FrameRing, shared_objects
from sim.process.worker_signals import ignore_sigint


def _worker_start() -> None:
    """Ignore Ctrl-C and SIGTERM (the mission process stops the worker), keep OpenCV to one
    thread and set the garbage collector for the loop (:mod:`sim.process.gc_policy`)."""
    import cv2

    from sim.process.gc_policy import set_loop_thresholds

    set_loop_thresholds()
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    ignore_sigint()  # blocked since the start (the mission process starts the workers so)
    cv2.setNumThreads(1)


def _command(conn: Any) -> tuple | None:
    """The next message from the mission process; None for ``("stop",)`` or a closed connection
    (the mission process ended)."""
    try:
        msg = conn.recv()
    except EOFError:
        return None
    return None if msg[0] == "stop" else msg


def _report(conn: Any) -> None:
    try:
        conn.send(("error", traceback.format_exc()))
    except (OSError, EOFError):
        pass


def render_main(conn: Any, to_detection: Any, ring_detection: FrameRing, to_main: Any,
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
        caster = MujocoRayCaster(model, data, s["geom_object_id"], s["geom_reflectivity"], s["vehicle_body_id"],
                                 backend=s["ray_caster"])
        objects, with_truth = s["objects"], s["truth_to_perception"]
        shared_ids = {id(v): name for name, v in shared_objects(sonar).items()}
        while True:
            msg = _command(conn)
            if msg is None:
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
            ring_detection.put(to_detection, (k, view), shared_ids)
            if ring_main is not None:
                ring_main.put(to_main, (k, render), shared_ids)
            conn.send(("rendered", k))
    except BaseException:
        _report(conn)
    finally:
        ring_detection.close()
        if ring_main is not None:
            ring_main.close()


def detection_main(conn: Any, from_render: Any, ring_in: FrameRing, to_main: Any, ring_out: FrameRing) -> None:
    """Detection-worker loop (see the module doc). The first message on ``conn`` (bytes): the
    pickled dict ``atr`` (the ATR config the detector is built from) and ``shared`` (the sonar's
    fixed tables, :func:`sim.process.frame_transport.shared_objects`)."""
    _worker_start()
    try:
        import dataclasses

        from autonomy.atr import build_detector

        s = pickle.loads(conn.recv_bytes())
        detector, shared = build_detector(s["atr"]), s["shared"]
        shared_ids = {id(v): name for name, v in shared.items()}
        sources = [conn, from_render]
        while True:
            for src in wait(sources):
                if src is conn:
                    if _command(conn) is None:
                        return
                    continue  # nothing else is asked of this worker
                try:
                    k, view = ring_in.get(from_render, shared)
                except EOFError:
                    sources.remove(from_render)  # the render worker ended (its error went to the mission)
                    continue
                detections = detector.detect(view.frame)
                # the frame without its images: what perception reads besides the detections
                frame = dataclasses.replace(view.frame, polar=None, fan=None)
                ring_out.put(to_main, (k, detections, dataclasses.replace(view, frame=frame)), shared_ids)
    except BaseException:
        _report(conn)
    finally:
        ring_in.close()
        ring_out.close()
