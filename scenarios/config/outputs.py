"""What a run writes besides its always-written files (metrics, trajectory, world model, map)."""

from __future__ import annotations

from pydantic import Field

from scenarios.config.base import StrictModel


class OutputsConfig(StrictModel):
    """Optional outputs of ``auvsim run`` (its ``--rosbag`` / ``--rosbag-fls-every`` /
    ``--ping360-log`` / ``--xtf`` flags override these).

    Attributes:
        rosbag: also write a ROS 2 bag (rosbag2 folder, MCAP storage) into ``OUT/rosbag``.
        rosbag_fls_every: export every n-th frame of each forward-looking sonar into the bag
            (1: all; a frame is ~0.8 MB).
        ping360_log: also write each scanning-sonar ping as a Blue Robotics ping-protocol
            ``PING360_DEVICE_DATA`` message into ``OUT/ping360/<sensor>.bin`` (with
            ``<sensor>.csv``: time, offset, angle; :mod:`sim.outputs.ping360_log`); needs a
            sensor of kind ``msis``.
        xtf: also write each side-scan sonar's pings as an eXtended Triton Format file
            ``OUT/xtf/<sensor>.xtf`` (:mod:`sim.outputs.xtf_log`); needs a sensor of kind ``sss``.
    """

    rosbag: bool = False
    rosbag_fls_every: int = Field(1, ge=1, le=1_000_000)
    ping360_log: bool = False
    xtf: bool = False
