"""Moving targets in the MuJoCo scene: mocap bodies for divers, small vehicles and bubbles.

:func:`add_mover_bodies` adds them to the world's MjSpec (acoustic geoms, labelled scene
objects); :class:`MovingBodies` draws each mover's seeded trajectory
(:mod:`sim.scene.target_motion`) and sets the mocap poses for a given time (what
:class:`sim.scene.physics.Physics` calls before every physics step and before sensors look).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from scenarios.config.movers import MoverConfig
from sim.rng import component_rng
from sim.scene.target_motion import PARKED_NED, BubblePlumes, ManoeuvreTrajectory, WaterDrift, plume_slots

FloatArray = NDArray[np.float64]
DIVER_RADIUS_M = 0.2  # capsule: a prone diver 1.8 m long (with fins), 0.4 m across
DIVER_HALF_LENGTH_M = 0.7
BUBBLE_CLASS = "bubble"  # class name of a plume's scatterers (parked above the surface between breaths)
VEHICLE_HALF_SIZE_M = (0.35, 0.35, 0.175)  # PlaDyPos, paper 004 section 5
_CAPSULE_ALONG_X = [math.cos(math.pi / 4), 0.0, math.sin(math.pi / 4), 0.0]  # local z -> x


@dataclass(frozen=True)
class MoverGeom:
    """A mover's (or bubble's) acoustic geom as added to the spec, for the world's tables."""

    geom: mujoco.MjsGeom
    body_name: str
    name: str
    class_name: str
    is_target: bool
    shape: str
    radius_m: float
    height_m: float
    reflectivity: float


def add_mover_bodies(spec: mujoco.MjSpec, movers: tuple[MoverConfig, ...], acoustic_group: int) -> list[MoverGeom]:
    """Add one mocap body per mover and per bubble, each with one acoustic geom at its origin.

    The diver and the vehicle collide with the hull (contacts report collisions); bubbles do not.
    """
    out = []
    for m in movers:
        body_name = f"mover:{m.name}"
        body = spec.worldbody.add_body(name=body_name, mocap=True, pos=list(m.initial_pos_ned))
        if m.kind == "diver":
            geom = body.add_geom(name=f"target:{m.name}", type=mujoco.mjtGeom.mjGEOM_CAPSULE,
                                 size=[DIVER_RADIUS_M, DIVER_HALF_LENGTH_M, 0.0], quat=_CAPSULE_ALONG_X,
                                 group=acoustic_group, rgba=[0.2, 0.3, 0.9, 1.0])
            radius, height = DIVER_HALF_LENGTH_M + DIVER_RADIUS_M, 2 * DIVER_RADIUS_M
        else:
            geom = body.add_geom(name=f"target:{m.name}", type=mujoco.mjtGeom.mjGEOM_BOX,
                                 size=list(VEHICLE_HALF_SIZE_M), group=acoustic_group, rgba=[0.9, 0.8, 0.1, 1.0])
            radius, height = float(np.linalg.norm(VEHICLE_HALF_SIZE_M)), 2 * VEHICLE_HALF_SIZE_M[2]
        out.append(MoverGeom(geom, body_name, m.name, m.class_name, True, m.kind, radius, height, m.reflectivity))
        if m.bubbles.enabled:
            b = m.bubbles
            n = plume_slots(b) * b.per_breath
            for i in range(n):
                bname = f"mover:{m.name}/bubble{i}"
                bb = spec.worldbody.add_body(name=bname, mocap=True, pos=PARKED_NED.tolist())
                g = bb.add_geom(name=f"target:{m.name}/bubble{i}", type=mujoco.mjtGeom.mjGEOM_SPHERE,
                                size=[b.radius_m, 0, 0], group=acoustic_group, contype=0, conaffinity=0,
                                rgba=[0.9, 0.9, 1.0, 0.6])
                out.append(MoverGeom(g, bname, f"{m.name}/bubble{i}", BUBBLE_CLASS, False, "sphere", b.radius_m,
                                     2 * b.radius_m, b.reflectivity))
    return out


class MovingBodies:
    """The scenario's movers, their trajectories for one seed, and their mocap slots.

    Args:
        model: the compiled scene (with the bodies of :func:`add_mover_bodies`).
        movers: the movers' configs.
        seed: root seed (each mover draws from ``component_rng(seed, "mover:<name>")``, its
            plume from ``"bubbles:<name>"``).
        duration_s: mission length to draw manoeuvres for, s.
        current: the water current (``velocity_tuple``, ``mean_ned``, ``sigma_mps`` as
            :class:`sim.dynamics.current.OceanCurrent`) that carries the bubbles; None: still water.
    """

    def __init__(self, model: mujoco.MjModel, movers: tuple[MoverConfig, ...], seed: int, duration_s: float,
                 current=None) -> None:
        self.movers = movers
        self.drift = WaterDrift()
        self._current = None
        self.set_current(current)
        self.trajectories: dict[str, ManoeuvreTrajectory] = {}
        self.plumes: dict[str, BubblePlumes] = {}
        self._slots: list[tuple[int, str]] = []  # mocap id of each mover body
        self._bubble_slots: dict[str, NDArray[np.intp]] = {}
        for m in movers:
            traj = ManoeuvreTrajectory(m, component_rng(seed, f"mover:{m.name}"), duration_s)
            self.trajectories[m.name] = traj
            bid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"mover:{m.name}")
            self._slots.append((int(model.body_mocapid[bid]), m.name))
            if m.bubbles.enabled:
                plume = BubblePlumes(m.bubbles, traj, component_rng(seed, f"bubbles:{m.name}"), duration_s,
                                     drift=self.drift)
                self.plumes[m.name] = plume
                ids = [int(model.body_mocapid[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY,
                                                                   f"mover:{m.name}/bubble{i}")])
                       for i in range(plume.n_bubbles)]
                self._bubble_slots[m.name] = np.array(ids, dtype=np.intp)

    def set_current(self, current) -> None:
        """Carry the bubbles with ``current`` from now on (its mean exactly, its varying part as
        :meth:`apply` sees it at each step)."""
        mean = np.zeros(3) if current is None else np.asarray(current.mean_ned, dtype=float)
        self.drift.mean_ned_mps[:] = mean
        self._current = current if current is not None and current.sigma_mps > 0.0 else None

    def __bool__(self) -> bool:
        return bool(self.movers)

    def apply(self, data: mujoco.MjData, t_s: float) -> None:
        """Set every mover's and bubble's mocap pose to its pose at ``t_s`` (and note the
        current in force from ``t_s`` for the bubbles' drift)."""
        if self._current is not None and self._bubble_slots:
            self.drift.record(t_s, self._current.velocity_tuple)
        for mid, name in self._slots:
            pos, course = self.trajectories[name].pose_at(t_s)
            data.mocap_pos[mid] = pos
            data.mocap_quat[mid] = (math.cos(0.5 * course), 0.0, 0.0, math.sin(0.5 * course))
        for name, ids in self._bubble_slots.items():
            pos, _ = self.plumes[name].positions_at(t_s)
            data.mocap_pos[ids] = pos
