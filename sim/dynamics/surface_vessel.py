"""A surface vessel in the scene: Fossen's 3-DOF horizontal-plane model on MuJoCo joints.

The hull (:func:`sim.dynamics.hull.build_hull_spec` of a ``surface_3dof`` preset) moves on a north
slide, an east slide and a yaw hinge, at its waterline depth, level. Heave, roll and pitch
are constrained rather than integrated: the simulator models no waves, so a floating hull
only sits at its hydrostatic equilibrium in those DOFs, and their stiff restoring modes
(heave period ~0.5 s for a 37 kg hull on ~0.5 m^2 of waterplane) would add nothing but cost
and step-size trouble.

Equations ([Fossen2021-3DOF] in ``docs/references.md``: Fossen 2021, *Handbook of Marine
Craft Hydrodynamics and Motion Control*, 2nd ed., ch. 6-7, the 3-DOF manoeuvring model with
the current: ``nu_r = nu - nu_c``)::

    M_RB nu_dot + C_RB(nu) nu + M_A nu_r_dot + C_A(nu_r) nu_r + D(nu_r) nu_r = tau
    nu = [u, v, r] (FRD, over ground), M_RB = diag(m, m, I_z), M_A = diag(X_udot, Y_vdot, N_rdot)
    C_RB(nu) nu   = [-m r v, m r u, 0]
    C_A(nu_r) nu_r = [-Y_vdot r v_r, X_udot r u_r, (Y_vdot - X_udot) u_r v_r]
    D(nu_r) nu_r  = (D_l + D_q |nu_r|) nu_r            (diagonal)
    nu_c_dot      = [r v_c, -r u_c, 0]                  (an NED-constant current seen from a turning hull)

with the CG on the yaw axis (``r_bg`` = 0 horizontally) and positive added mass (the
preset's surge, sway and yaw entries of ``added_mass`` / damping). ``nu_dot`` is solved
exactly ((M_RB + M_A) is diagonal), and MuJoCo gets the joint forces that make its rigid
body accelerate so: with the CG on the hinge the joint-space mass matrix is diag(m, m, I_z)
and has no bias terms, so ``qfrc = [m a_n, m a_e, I_z r_dot]`` with the CO acceleration
over ground ``a_ned = R(psi) [u_dot - r v, v_dot + r u]``. Held over a step (explicit, as
:mod:`sim.dynamics.vehicle`).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.frames import rot_from_euler
from sim.dynamics.current import OceanCurrent
from sim.dynamics.thrusters import ThrusterArray
from sim.dynamics.truth import VehicleTruth
from scenarios.vehicle_params import VehicleParams

FloatArray = NDArray[np.float64]
SURGE, SWAY, YAW = 0, 1, 5  # rows of the 6-DOF preset matrices this model uses


def horizontal_coefficients(params: VehicleParams) -> dict[str, tuple[float, float, float]]:
    """The 3-DOF coefficients of a ``surface_3dof`` preset: ``rigid`` (m, m, I_z), ``added``
    (X_udot, Y_vdot, N_rdot), ``linear`` and ``quadratic`` damping (surge, sway, yaw).

    Raises:
        ValueError: the preset is not ``surface_3dof``, its CG is off the yaw axis, or its
            added mass / damping couple surge, sway and yaw (not in this model).
    """
    if params.motion != "surface_3dof":
        raise ValueError(f"{params.name}: motion is {params.motion!r}, not 'surface_3dof'")
    if np.any(np.abs(params.r_bg_m[:2]) > 1e-12):
        raise ValueError(f"{params.name}: the 3-DOF surface model needs the CG on the yaw axis (r_bg_m x, y = 0)")
    idx = (SURGE, SWAY, YAW)
    for key in ("added_mass", "damping_linear", "damping_quadratic"):
        sub = getattr(params, key)[np.ix_(idx, idx)]
        if np.any(np.abs(sub - np.diag(np.diag(sub))) > 1e-12):
            raise ValueError(f"{params.name}: '{key}' couples surge, sway and yaw; the 3-DOF model takes it diagonal")
    if np.any(params.damping_linear_decay_spm[list(idx)] != 0.0):
        raise ValueError(f"{params.name}: 'damping_linear_decay_spm' is not modelled for surface_3dof")
    m, iz = params.mass_kg, float(params.inertia_co_kgm2[2, 2])
    diag = lambda M: tuple(float(M[i, i]) for i in idx)  # noqa: E731
    return {"rigid": (m, m, iz), "added": diag(params.added_mass), "linear": diag(params.damping_linear),
            "quadratic": diag(params.damping_quadratic)}


def horizontal_acceleration(params: VehicleParams, nu: ArrayLike, current_body: ArrayLike,
                            tau: ArrayLike) -> FloatArray:
    """Reference ``nu_dot = [u_dot, v_dot, r_dot]`` (3,) of the module's equations (vector form).

    Args:
        nu: (3,) [u, v, r] over ground, m/s and rad/s (FRD).
        current_body: (2,) current [u_c, v_c] in body axes, m/s.
        tau: (3,) [X, Y, N] control force (N) and yaw moment (N m).
    """
    c = horizontal_coefficients(params)
    u, v, r = (float(x) for x in nu)
    uc, vc = (float(x) for x in current_body)
    nr = np.array([u - uc, v - vc, r])
    m, _, _ = c["rigid"]
    xa, ya, _ = c["added"]
    crb = np.array([-m * r * v, m * r * u, 0.0])
    ca = np.array([-ya * r * nr[1], xa * r * nr[0], (ya - xa) * nr[0] * nr[1]])
    d = (np.array(c["linear"]) + np.array(c["quadratic"]) * np.abs(nr)) * nr
    nuc_dot = np.array([r * vc, -r * uc, 0.0])
    M = np.array(c["rigid"]) + np.array(c["added"])
    return (np.asarray(tau, dtype=float) - crb - ca - d + np.array(c["added"]) * nuc_dot) / M


class SurfaceVesselDynamics:
    """A ``surface_3dof`` vessel bound to one ``MjModel`` / ``MjData``.

    Args:
        model, data: compiled scene holding the hull.
        params: a ``surface_3dof`` preset.
        body_id: the hull body's id in ``model``.
        current: the scene's :class:`OceanCurrent` (advanced by its owner), or ``None``.

    Attributes:
        command: (n_thr,) normalised thruster commands held until changed
            (:meth:`set_command`), applied by :meth:`step_inputs`.

    Raises:
        ValueError: see :func:`horizontal_coefficients`; the body lacks the slide/hinge joints.
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, params: VehicleParams, body_id: int,
                 current: OceanCurrent | None = None) -> None:
        c = horizontal_coefficients(params)
        self.model, self.data, self.params, self.body_id = model, data, params, int(body_id)
        jnt0, njnt = int(model.body_jntadr[body_id]), int(model.body_jntnum[body_id])
        types = [int(model.jnt_type[jnt0 + k]) for k in range(njnt)] if jnt0 >= 0 else []
        slide, hinge = int(mujoco.mjtJoint.mjJNT_SLIDE), int(mujoco.mjtJoint.mjJNT_HINGE)
        if types != [slide, slide, hinge]:
            raise ValueError(f"{params.name}: the hull body needs north/east slides and a yaw hinge")
        self._q = int(model.jnt_qposadr[jnt0])
        self._v = int(model.jnt_dofadr[jnt0])
        self._z = float(model.body_pos[body_id][2])
        self._m, _, self._iz = c["rigid"]
        self._xa, self._ya, self._na = c["added"]
        self._minv = tuple(1.0 / (a + b) for a, b in zip(c["rigid"], c["added"]))
        self._dl, self._dq = c["linear"], c["quadratic"]
        self.thrusters = ThrusterArray(params)
        self.command = np.zeros(self.thrusters.n)
        self._qpos = data.qpos[self._q:self._q + 3]
        self._qvel = data.qvel[self._v:self._v + 3]
        self._qfrc = data.qfrc_applied[self._v:self._v + 3]
        self._tau = [0.0] * 6
        self._nu_dot = (0.0, 0.0, 0.0)
        self.current = current

    def set_current(self, current: OceanCurrent | None) -> None:
        """Use ``current`` (its present value; its owner advances it) from the next step on."""
        self.current = current

    def set_command(self, cmd: ArrayLike) -> None:
        """Hold normalised thruster commands (n_thr,) in [-1, 1] from the next step on.

        Raises:
            ValueError: wrong length.
        """
        cmd = np.asarray(cmd, dtype=float)
        if cmd.shape != (self.thrusters.n,):
            raise ValueError(f"{self.params.name}: thruster command needs {self.thrusters.n} values "
                             f"{self.thrusters.layout.names}, got shape {cmd.shape}")
        self.command = cmd.copy()

    def reset(self, pos_ne_m: ArrayLike, heading_rad: float) -> None:
        """At rest at ``pos_ne_m`` (2,) (north, east, m) with heading ``heading_rad``, rotors
        stopped, commands zero."""
        n, e = (float(x) for x in pos_ne_m)
        self._qpos[:] = (n, e, float(heading_rad))
        self._qvel[:] = 0.0
        self._qfrc[:] = 0.0
        self.thrusters.reset()
        self.command = np.zeros(self.thrusters.n)
        self._tau = [0.0] * 6
        self._nu_dot = (0.0, 0.0, 0.0)

    def _accel(self, u: float, v: float, r: float, c: float, s: float) -> tuple[float, float, float]:
        """Scalar fast path of :func:`horizontal_acceleration` with heading cos/sin ``c``, ``s``."""
        cur = self.current
        if cur is None or cur.is_still:
            uc = vc = 0.0
        else:
            cn, ce, _ = cur.velocity_tuple
            uc, vc = c * cn + s * ce, -s * cn + c * ce
        ur, vr = u - uc, v - vc
        tau = self._tau
        dl, dq = self._dl, self._dq
        m, xa, ya = self._m, self._xa, self._ya
        fx = tau[0] + m * r * v + ya * r * vr - (dl[0] + dq[0] * abs(ur)) * ur + xa * r * vc
        fy = tau[1] - m * r * u - xa * r * ur - (dl[1] + dq[1] * abs(vr)) * vr - ya * r * uc
        fn = tau[5] - (ya - xa) * ur * vr - (dl[2] + dq[2] * abs(r)) * r
        mi = self._minv
        return fx * mi[0], fy * mi[1], fn * mi[2]

    def step_inputs(self, dt_s: float) -> None:
        """Advance the rotors by ``dt_s`` under :attr:`command` and write the joint forces
        into ``data.qfrc_applied``. Call right before each ``mujoco.mj_step``."""
        self._tau = self.thrusters.step(self.command, dt_s)
        psi = self._qpos[2]
        c, s = math.cos(psi), math.sin(psi)
        vn, ve, r = self._qvel.tolist()
        u, v = c * vn + s * ve, -s * vn + c * ve
        ud, vd, rd = self._accel(u, v, r, c, s)
        self._nu_dot = (ud, vd, rd)
        ax, ay = ud - r * v, vd + r * u
        m = self._m
        self._qfrc[:] = (m * (c * ax - s * ay), m * (s * ax + c * ay), self._iz * rd)

    # ------------------------------------------------------------------ readouts
    def truth(self, t_s: float) -> VehicleTruth:
        """Ground truth at ``t_s`` as a 6-DOF snapshot (level, at the waterline depth):
        ``nu = [u, v, 0, 0, 0, r]``; ``nu_dot`` at the present state and thrust."""
        n, e, psi = self._qpos.tolist()
        c, s = math.cos(psi), math.sin(psi)
        vn, ve, r = self._qvel.tolist()
        u, v = c * vn + s * ve, -s * vn + c * ve
        ud, vd, rd = self._accel(u, v, r, c, s)
        cur = np.zeros(3) if self.current is None else self.current.velocity_ned
        return VehicleTruth(
            t_s=float(t_s), pos_ned=np.array([n, e, self._z]), R_nb=rot_from_euler(0.0, 0.0, psi),
            rpy_rad=np.array([0.0, 0.0, math.atan2(s, c)]), nu=np.array([u, v, 0.0, 0.0, 0.0, r]),
            nu_dot=np.array([ud, vd, 0.0, 0.0, 0.0, rd]), current_ned=cur)

    def allocate(self, wrench_body: ArrayLike) -> FloatArray:
        """Thruster commands (n,) for a desired body wrench (6,) (surge X, sway Y, yaw N used)."""
        return self.thrusters.allocate(wrench_body)
