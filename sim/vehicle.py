"""Thin MuJoCo adapter: thrusters + Fossen wrench onto the vehicle body each physics step.

Usage per physics step::

    dyn.step_inputs(thruster_cmd, dt_s)   # rotors, current, hydrodynamic wrench -> xfrc_applied
    mujoco.mj_step(model, data)

MuJoCo integrates the rigid body (gravity off); :class:`sim.hydrodynamics.FossenModel`
supplies the wrench that makes it follow Fossen's equations with added mass solved exactly
(see that module). Free-joint conventions used here: ``qpos = [pos of CO in NED, quat wxyz]``,
``qvel = [velocity of CO in NED, angular velocity in body axes]``; ``xfrc_applied`` is a
world-frame force and torque about the body's CoM.

The hot path uses plain ``mujoco`` arrays: ``dm_control.mujoco.Physics`` named indexing
costs microseconds per access, more than the whole wrench computation.
"""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.frames import euler_from_rot, quat_from_euler, rot_from_quat
from scenarios.config.world import CurrentConfig
from sim.current import OceanCurrent
from sim.hydrodynamics import FossenModel
from sim.hull import VEHICLE_BODY
from sim.thrusters import ThrusterArray
from sim.truth import VehicleTruth
from sim.vehicle_params import VehicleParams

FloatArray = NDArray[np.float64]


def find_vehicle_body(model: mujoco.MjModel) -> int:
    """Id of the body named ``vehicle`` (with or without an attach prefix)."""
    for bid in range(model.nbody):
        name = model.body(bid).name
        if name == VEHICLE_BODY or name.endswith("/" + VEHICLE_BODY):
            return bid
    raise ValueError(f"model has no body named '{VEHICLE_BODY}' (or '<prefix>/{VEHICLE_BODY}')")


class VehicleDynamics:
    """Vehicle physics bound to one ``MjModel`` / ``MjData``.

    Args:
        model, data: compiled scene holding the hull (:func:`sim.hull.build_hull_spec`).
        params: the vehicle's parameters.
        current: an :class:`OceanCurrent`, a :class:`CurrentConfig` (built with ``rng``),
            or ``None`` for still water.
        rng: generator for the current's Gauss-Markov part (``component_rng(seed, "current")``).
        body_id: vehicle body id (default: found by name).
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, params: VehicleParams,
                 current: OceanCurrent | CurrentConfig | None = None,
                 rng: np.random.Generator | None = None, *, body_id: int | None = None) -> None:
        self.model, self.data, self.params = model, data, params
        self.body_id = find_vehicle_body(model) if body_id is None else int(body_id)
        jnt = model.body_jntadr[self.body_id]
        if jnt < 0 or model.jnt_type[jnt] != mujoco.mjtJoint.mjJNT_FREE:
            raise ValueError("the vehicle body needs a free joint")
        self._qadr = int(model.jnt_qposadr[jnt])
        self._vadr = int(model.jnt_dofadr[jnt])
        if isinstance(current, CurrentConfig):
            current = OceanCurrent(current, rng)
        self.current = current
        self.fossen = FossenModel(params)
        self.thrusters = ThrusterArray(params)
        # Views, so the hot path does no lookups.
        q, v = self._qadr, self._vadr
        self._quat = data.qpos[q + 3:q + 7]
        self._depth = data.qpos[q + 2:q + 3]
        self._vel = data.qvel[v:v + 3]
        self._omega = data.qvel[v + 3:v + 6]
        self._xfrc = data.xfrc_applied[self.body_id]
        self._tau_thr = [0.0] * 6

    # ------------------------------------------------------------------ state handling
    def reset(self, pos_ned: ArrayLike, rpy_rad: ArrayLike) -> None:
        """Place the vehicle at rest at ``pos_ned`` (CO, m) with attitude ``rpy_rad``."""
        q, v = self._qadr, self._vadr
        self.data.qpos[q:q + 3] = np.asarray(pos_ned, dtype=float)
        self.data.qpos[q + 3:q + 7] = quat_from_euler(*np.asarray(rpy_rad, dtype=float))
        self.data.qvel[v:v + 6] = 0.0
        self.data.xfrc_applied[self.body_id] = 0.0
        self.thrusters.reset()
        if self.current is not None:
            self.current.reset()
        self._tau_thr = [0.0] * 6
        mujoco.mj_forward(self.model, self.data)

    def step_inputs(self, thruster_cmd: ArrayLike, dt_s: float) -> None:
        """Advance rotors and current by ``dt_s`` and write the vehicle wrench into
        ``data.xfrc_applied``. Call right before each ``mujoco.mj_step``."""
        tau = self.thrusters.step(thruster_cmd, dt_s)
        self._tau_thr = tau
        cur = self.current
        if cur is None or cur.is_still:
            c = None
        else:
            c = cur.step(dt_s)
        # tolist(): scalar arithmetic on Python floats is several times faster than on
        # numpy scalars.
        self._xfrc[:] = self.fossen.mujoco_wrench(self._quat.tolist(), self._vel.tolist(),
                                                  self._omega.tolist(), c, tau,
                                                  self._depth.item())

    # ------------------------------------------------------------------------ readouts
    @property
    def current_ned(self) -> FloatArray:
        return np.zeros(3) if self.current is None else self.current.velocity_ned

    def nu(self) -> FloatArray:
        """(6,) body velocity over ground [u, v, w, p, q, r]."""
        R = rot_from_quat(self._quat)
        return np.concatenate([R.T @ self._vel, self._omega])

    def truth(self, t_s: float) -> VehicleTruth:
        """Ground-truth snapshot; ``nu_dot`` is evaluated at the present state with the
        present thrust (not the acceleration of the step just taken)."""
        q = self._qadr
        quat = np.array(self._quat)
        R = rot_from_quat(quat)
        cur = None if self.current is None or self.current.is_still else self.current.velocity_tuple
        self.fossen.mujoco_wrench(quat.tolist(), self._vel.tolist(), self._omega.tolist(), cur,
                                  self._tau_thr, self._depth.item())
        nu = np.array(self.fossen.nu)
        return VehicleTruth(
            t_s=float(t_s),
            pos_ned=np.array(self.data.qpos[q:q + 3]),
            R_nb=R,
            rpy_rad=euler_from_rot(R),
            nu=nu,
            nu_dot=self.fossen.nu_dot(),
            current_ned=self.current_ned,
        )

    def allocate(self, wrench_body: ArrayLike) -> FloatArray:
        """Thruster commands (n,) for a desired body wrench (6,)."""
        return self.thrusters.allocate(wrench_body)
