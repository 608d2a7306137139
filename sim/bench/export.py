"""Export benchmark: the CPU cost of each field-format writer per simulated minute.

``auvsim bench export`` flies three shipped missions, each with one writer, and times the
writer's observer hooks alone (process CPU time inside ``on_start`` / ``on_message`` /
``on_step`` / ``on_end``), so the figure is the export's own cost, not the mission's:

| writer | mission | what it writes |
|---|---|---|
| ``rosbag`` (``--rosbag``) | ``cssn_lawnmower``, every sonar frame | ROS 2 bag, MCAP storage |
| ``xtf`` (``--xtf``) | ``mcm_survey_full`` | side-scan pings, eXtended Triton Format |
| ``ping360_log`` (``--ping360-log``) | ``pool_circular`` | ping-protocol ``PING360_DEVICE_DATA`` messages |

A writer whose package is missing (the ``rosbag``, ``xtf``, ``ping`` extras) is reported as
``skipped`` with the install hint.
"""

from __future__ import annotations

import importlib.util
import tempfile
import time
from pathlib import Path
from typing import Any

from sim.events.records import MissionObserver
from sim.outputs.ping360_log import Ping360LogRecorder


class TimedObserver:
    """An observer that forwards every hook to ``inner`` and adds up the process CPU time
    spent there (``cpu_s``); it declares what ``inner`` declares (``sonar_frames``,
    ``sonar_truth``)."""

    def __init__(self, inner: MissionObserver) -> None:
        self.inner = inner
        self.cpu_s = 0.0
        self.sonar_frames = getattr(inner, "sonar_frames", True)
        self.sonar_truth = getattr(inner, "sonar_truth", True)

    def _timed(self, hook: str, *args: Any) -> None:
        t0 = time.process_time()
        getattr(self.inner, hook)(*args)
        self.cpu_s += time.process_time() - t0

    def on_start(self, info: Any) -> None:
        self._timed("on_start", info)

    def on_step(self, record: Any) -> None:
        self._timed("on_step", record)

    def on_message(self, name: str, msg: Any) -> None:
        self._timed("on_message", name, msg)

    def on_end(self, summary: Any) -> None:
        self._timed("on_end", summary)


def _writers() -> list[tuple[str, str, str, list[str], str]]:
    """(writer, module needed, scenario, overrides, install hint)."""
    return [
        ("rosbag", "rosbags", "cssn_lawnmower", ["autonomy.atr.detector=classical"], "pip install 'auvsim[rosbag]'"),
        ("xtf", "pyxtf", "mcm_survey_full", [], "pip install 'auvsim[xtf]'"),
        ("ping360_log", "brping", "pool_circular", [], "pip install 'auvsim[ping]'"),
    ]


def _recorder(writer: str, folder: Path) -> MissionObserver:
    if writer == "rosbag":
        from sim.ros2bag.recorder import RosbagRecorder

        return RosbagRecorder(folder / "rosbag")
    if writer == "xtf":
        from sim.outputs.xtf_log import XtfRecorder

        return XtfRecorder(folder / "xtf")

    return Ping360LogRecorder(folder / "ping360")


def run(seed: int = 0, duration_s: float = 30.0) -> dict:
    """Time each writer over ``duration_s`` of its mission.

    Returns:
        dict: per writer, ``cpu_s_per_sim_min`` (the writer's CPU seconds per simulated
        minute), ``share_of_run`` (its fraction of the run's CPU time), ``run_cpu_s_per_sim_min``,
        ``bytes_per_sim_min`` (what it wrote) and ``mission``; or ``skipped`` and the hint.
    """
    from scenarios import load_scenario
    from sim.mission import Mission

    out: dict[str, Any] = {"duration_s": duration_s}
    for writer, module, scenario_name, overrides, hint in _writers():
        if importlib.util.find_spec(module) is None:
            out[writer] = {"skipped": f"needs {module} ({hint})"}
            continue
        scn = load_scenario(scenario_name, [f"seed={seed}", f"duration_s={duration_s}", *overrides])
        with tempfile.TemporaryDirectory() as tmp:
            timed = TimedObserver(_recorder(writer, Path(tmp)))
            c0 = time.process_time()
            Mission(scn, observers=[timed]).run(progress=False)
            run_cpu = time.process_time() - c0
            size = sum(p.stat().st_size for p in Path(tmp).rglob("*") if p.is_file())
        minutes = duration_s / 60.0
        out[writer] = {"mission": scenario_name, "cpu_s_per_sim_min": round(timed.cpu_s / minutes, 4),
                       "share_of_run": round(timed.cpu_s / run_cpu, 4),
                       "run_cpu_s_per_sim_min": round(run_cpu / minutes, 3),
                       "bytes_per_sim_min": int(size / minutes)}
    return out
