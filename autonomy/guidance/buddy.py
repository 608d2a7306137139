"""Buddy observer: follow a tracked target (a diver) keeping it in the sonar's view at a set
distance (paper 004's motivating use: an AUV as a diver's buddy, docs/references.md [P004]).

From the target's estimated NED position and the vehicle's navigation estimate: heading
towards the target (the sonar looks along the bow), surge proportional to the range error
along the horizontal line of sight, clipped; a floor distance under which the vehicle backs
off. Before the tracker has an estimate the vehicle holds its start heading and depth.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from autonomy.control.setpoint import Setpoint
from autonomy.guidance.config import BuddyConfig
from autonomy.messages import NavEstimate


class BuddyObserver:
    """Setpoints that keep a target ahead at ``cfg.distance_m``.

    Args:
        cfg: distances (m), gain (1/s), speed limit (m/s), depth rule.
        initial_heading_rad: heading held before the first target estimate, NED rad.
        initial_depth_m: depth held before the first target estimate, m.
    """

    def __init__(self, cfg: BuddyConfig, initial_heading_rad: float, initial_depth_m: float) -> None:
        self.cfg = cfg
        self._heading = float(initial_heading_rad)
        self._depth = float(cfg.depth_m if cfg.depth_m is not None else initial_depth_m)

    def update(self, nav: NavEstimate, target_pos_ned: ArrayLike | None) -> Setpoint:
        """Setpoint from the vehicle estimate and the target's (3,) NED position estimate, m
        (None: no estimate yet).

        Raises:
            ValueError: a non-finite target position.
        """
        cfg = self.cfg
        if target_pos_ned is None or cfg.behaviour == "hover":
            return Setpoint(0.0, self._heading, depth_m=self._depth)
        tgt = np.asarray(target_pos_ned, dtype=float).reshape(3)
        if not np.all(np.isfinite(tgt)):
            raise ValueError(f"BuddyObserver.update: target position not finite: {tgt}")
        d_ne = tgt[:2] - np.asarray(nav.pos_ned[:2], dtype=float)
        rng = float(math.hypot(*d_ne))
        if rng > 1e-3:
            self._heading = math.atan2(d_ne[1], d_ne[0])
        if cfg.depth_m is None:
            self._depth = max(float(tgt[2]) - cfg.depth_offset_m, 0.3)
        speed = 0.0
        if cfg.behaviour == "follow":
            speed = float(np.clip(cfg.gain_per_s * (rng - cfg.distance_m), -cfg.max_speed_mps, cfg.max_speed_mps))
        if rng < cfg.min_distance_m:  # too close, whatever the behaviour: back off
            speed = -cfg.max_speed_mps
        return Setpoint(speed, self._heading, depth_m=self._depth)
