"""Fossen's 6-DOF underwater-vehicle model (pure numpy).

State: body velocity over ground ``nu = [u, v, w, p, q, r]`` (FRD, about the centre of
origin CO), attitude ``R_nb`` (body->NED) and the water current ``v_c`` (NED, m/s). With
the relative velocity ``nu_r = nu - [R_nb^T v_c, 0]`` the equations of motion are
(Fossen 2021, eqs. 8.1-8.3, mixed ground/relative form)::

    M_RB nu_dot + C_RB(nu) nu + M_A nu_r_dot + C_A(nu_r) nu_r + D(nu_r) nu_r + g(eta) = tau

* ``M_RB``: rigid body about CO with the CG at ``r_bg``; ``C_RB`` its Coriolis/centripetal
  terms (Newton-Euler about CO).
* ``M_A`` (full 6x6 allowed) and ``C_A(nu_r)`` from the skew-symmetric parametrisation
  ``C_A = [[0, -S(A11 nu1 + A12 nu2)], [-S(A11 nu1 + A12 nu2), -S(A21 nu1 + A22 nu2)]]``;
  with ``params.munk_moments`` False the entries (0,4), (0,5), (1,5), (2,4), (4,0), (4,2),
  (5,0), (5,1) are zeroed (Fossen's bare-hull simplification, e.g. his REMUS 100).
* ``D(nu_r) nu_r = D_l' nu_r + D_q (|nu_r| * nu_r)``, where row ``i`` of ``D_l'`` is row
  ``i`` of ``D_l`` times ``exp(-k_i |v_r|)`` (``k`` = ``damping_linear_decay_spm``).
* ``g(eta)``: weight at CG and buoyancy at CB. Near the free surface (z = 0) the buoyancy
  is scaled by the submerged fraction of the hull height,
  ``clip((z + c_z + h/2) / h, 0, 1)`` (attitude ignored, CB kept at ``r_bb``), so a
  positively buoyant vehicle floats at the surface instead of flying out of the water.
* Current: ``nu_r_dot = nu_dot - nu_c_dot``. The current is constant or slowly varying in
  NED; we keep the exact frame-rotation part ``d/dt (R^T v_c) = -omega x (R^T v_c)`` and
  neglect the NED time derivative of the (Gauss-Markov) current itself.

**Added mass, exactly.** Collecting the acceleration terms gives the linear system
``(M_RB + M_A) nu_dot = tau - C_RB(nu) nu - C_A(nu_r) nu_r - D nu_r - g + M_A nu_c_dot``,
solved with the precomputed inverse of ``M`` (no finite differencing of accelerations,
no lag). MuJoCo integrates the *rigid body* only (its mass/inertia are ``m`` and ``I_g``),
and MuJoCo computes its own rigid-body Coriolis/gyroscopic terms. So the wrench handed to
MuJoCo is the one that makes the rigid body accelerate at ``nu_dot``::

    tau_mj = M_RB nu_dot + C_RB(nu) nu = K rhs + C_RB(nu) nu,   K = M_RB M^-1

expressed about CO in body axes; :meth:`FossenModel.mujoco_wrench` converts it to
MuJoCo's ``xfrc_applied`` convention (world-frame force, and torque about the body's CoM).

:class:`FossenModel` is the fast path used every physics step (scalar arithmetic on
precomputed constants, no per-step 6x6 matrix builds). The module-level matrix functions
are the readable reference used by the tests to check it.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.frames import skew
from scenarios.vehicle_params import VehicleParams

FloatArray = NDArray[np.float64]


# ----------------------------------------------------------------- matrix-form reference
def coriolis_matrix(M: ArrayLike, nu: ArrayLike) -> FloatArray:
    """(6, 6) Coriolis-centripetal matrix of a (6, 6) mass matrix (Fossen Thm. 3.2)."""
    M = np.asarray(M, dtype=float)
    nu = np.asarray(nu, dtype=float)
    a1 = M[:3, :3] @ nu[:3] + M[:3, 3:] @ nu[3:]
    a2 = M[3:, :3] @ nu[:3] + M[3:, 3:] @ nu[3:]
    Z = np.zeros((3, 3))
    return np.block([[Z, -skew(a1)], [-skew(a1), -skew(a2)]])


MUNK_ENTRIES = ((0, 4), (0, 5), (1, 5), (2, 4), (4, 0), (4, 2), (5, 0), (5, 1))


def added_mass_coriolis(params: VehicleParams, nu_r: ArrayLike) -> FloatArray:
    """(6, 6) C_A(nu_r), Munk entries zeroed when ``params.munk_moments`` is False."""
    C = coriolis_matrix(params.added_mass, nu_r)
    if not params.munk_moments:
        for i, j in MUNK_ENTRIES:
            C[i, j] = 0.0
    return C


def damping_matrix(params: VehicleParams, nu_r: ArrayLike) -> FloatArray:
    """(6, 6) D(nu_r) with ``D(nu_r) @ nu_r`` the damping force (sign: resists motion)."""
    nu_r = np.asarray(nu_r, dtype=float)
    speed = np.linalg.norm(nu_r[:3])
    D_l = params.damping_linear * np.exp(-params.damping_linear_decay_spm * speed)[:, None]
    return D_l + params.damping_quadratic * np.abs(nu_r)[None, :]


def submerged_fraction(params: VehicleParams, depth_m: float) -> float:
    """Fraction of the hull height below the surface when CO is at depth ``depth_m``."""
    h = float(params.hull.size_m[2])
    return min(max((depth_m + float(params.hull.center_body_m[2]) + 0.5 * h) / h, 0.0), 1.0)


def restoring_forces(params: VehicleParams, R_nb: ArrayLike, depth_m: float = np.inf) -> FloatArray:
    """(6,) g(eta): weight W at r_bg and buoyancy B at r_bb, body frame (Fossen eq. 4.6).
    ``depth_m`` (of CO) scales B by :func:`submerged_fraction`."""
    R = np.asarray(R_nb, dtype=float)
    buoyancy = params.buoyancy_n * submerged_fraction(params, depth_m)
    f_g = R.T @ np.array([0.0, 0.0, params.weight_n])
    f_b = R.T @ np.array([0.0, 0.0, -buoyancy])
    return -np.concatenate([f_g + f_b, np.cross(params.r_bg_m, f_g) + np.cross(params.r_bb_m, f_b)])


def current_body(R_nb: ArrayLike, current_ned: ArrayLike, nu: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Current in body axes ``nu_c`` (6,) and its body-frame rate ``nu_c_dot`` (6,)."""
    vc = np.asarray(R_nb, dtype=float).T @ np.asarray(current_ned, dtype=float)
    omega = np.asarray(nu, dtype=float)[3:]
    return np.concatenate([vc, np.zeros(3)]), np.concatenate([-np.cross(omega, vc), np.zeros(3)])


def acceleration(params: VehicleParams, nu: ArrayLike, R_nb: ArrayLike,
                 current_ned: ArrayLike, tau: ArrayLike, depth_m: float = np.inf) -> FloatArray:
    """Reference ``nu_dot`` (6,) from the full matrix equations (see module docstring)."""
    nu = np.asarray(nu, dtype=float)
    nu_c, nu_c_dot = current_body(R_nb, current_ned, nu)
    nu_r = nu - nu_c
    M_RB = params.rigid_body_mass
    M_A = params.added_mass
    rhs = (np.asarray(tau, dtype=float) - coriolis_matrix(M_RB, nu) @ nu
           - added_mass_coriolis(params, nu_r) @ nu_r - damping_matrix(params, nu_r) @ nu_r
           - restoring_forces(params, R_nb, depth_m) + M_A @ nu_c_dot)
    return np.linalg.solve(M_RB + M_A, rhs)


def rigid_body_wrench(params: VehicleParams, nu: ArrayLike, nu_dot: ArrayLike) -> FloatArray:
    """Reference ``M_RB nu_dot + C_RB(nu) nu`` (6,): the wrench about CO (body axes) a
    free rigid body needs to accelerate at ``nu_dot``."""
    M_RB = params.rigid_body_mass
    nu = np.asarray(nu, dtype=float)
    return M_RB @ np.asarray(nu_dot, dtype=float) + coriolis_matrix(M_RB, nu) @ nu


# ------------------------------------------------------------------------------ fast path
class FossenModel:
    """Per-step evaluation of the model on precomputed constants.

    Call :meth:`mujoco_wrench` once per physics step; it also leaves ``nu`` and the
    acceleration right-hand side for :meth:`nu_dot`.
    """

    def __init__(self, params: VehicleParams) -> None:
        self.params = params
        M_RB = params.rigid_body_mass
        M = M_RB + params.added_mass
        M_inv = np.linalg.inv(M)
        self._M_inv = M_inv
        K = M_RB @ M_inv
        self._K = [tuple(float(x) for x in row) for row in K]
        # K is mostly diagonal for real vehicles: diagonal + a short list of couplings.
        tol = 1e-14 * float(np.max(np.abs(K)))
        self._K_diag = tuple(float(x) for x in np.diag(K))
        self._K_off = tuple((i, j, float(K[i, j])) for i in range(6) for j in range(6)
                            if i != j and abs(K[i, j]) > tol)
        self._K_sparse = len(self._K_off) <= 12
        self._MA = [tuple(float(x) for x in row) for row in params.added_mass]
        self._MA_diag = tuple(float(x) for x in np.diag(params.added_mass))
        self._diag_added_mass = bool(np.all(params.added_mass == np.diag(self._MA_diag)))
        self._m = params.mass_kg
        self._rg = tuple(float(x) for x in params.r_bg_m)
        self._Io = [tuple(float(x) for x in row) for row in params.inertia_co_kgm2]
        W, B = params.weight_n, params.buoyancy_n
        self._W, self._B = float(W), float(B)
        self._rg_W = tuple(float(x) for x in W * params.r_bg_m)
        self._rb = tuple(float(x) for x in params.r_bb_m)
        self._W_minus_B = W - B
        self._moment_arm = tuple(float(x) for x in W * params.r_bg_m - B * params.r_bb_m)
        h = float(params.hull.size_m[2])
        self._hull_h = h
        self._emerge_depth = 0.5 * h - float(params.hull.center_body_m[2])  # CO depth: top at z=0
        self._bottom_off = float(params.hull.center_body_m[2]) + 0.5 * h
        Dl, Dq = params.damping_linear, params.damping_quadratic
        self._diag_damping = bool(np.all(Dl == np.diag(np.diag(Dl))) and np.all(Dq == np.diag(np.diag(Dq))))
        self._Dl = [tuple(float(x) for x in row) for row in Dl]
        self._Dq = [tuple(float(x) for x in row) for row in Dq]
        self._dl_diag = tuple(float(x) for x in np.diag(Dl))
        self._dq_diag = tuple(float(x) for x in np.diag(Dq))
        self._decay = tuple(float(x) for x in params.damping_linear_decay_spm)
        self._has_decay = any(k != 0.0 for k in self._decay)
        self._munk = bool(params.munk_moments)
        self.nu: tuple[float, ...] = (0.0,) * 6
        self.rhs: tuple[float, ...] = (0.0,) * 6

    def nu_dot(self) -> FloatArray:
        """(6,) body acceleration of the last :meth:`mujoco_wrench` evaluation."""
        return self._M_inv @ np.asarray(self.rhs)

    def mujoco_wrench(self, quat_wxyz, vel_world, omega_body, current_ned, tau_body,
                      depth_m: float = math.inf):
        """MuJoCo ``xfrc_applied`` row for the vehicle body.

        Args:
            quat_wxyz: body orientation (4,) (MuJoCo free-joint quaternion, unit).
            vel_world: (3,) velocity of the body origin CO in NED (free-joint qvel[0:3]).
            omega_body: (3,) body angular rate (free-joint qvel[3:6]).
            current_ned: (3,) water current in NED, or ``None`` for still water.
            tau_body: (6,) external control wrench about CO in body axes (thrusters).
            depth_m: depth of CO (m), for the buoyancy loss at the surface.

        Returns:
            list of 6 floats: world-frame force (N) and torque about the body CoM (N m).
        """
        qw, qx, qy, qz = quat_wxyz
        # R_nb from the unit quaternion.
        r00 = 1.0 - 2.0 * (qy * qy + qz * qz); r01 = 2.0 * (qx * qy - qw * qz); r02 = 2.0 * (qx * qz + qw * qy)
        r10 = 2.0 * (qx * qy + qw * qz); r11 = 1.0 - 2.0 * (qx * qx + qz * qz); r12 = 2.0 * (qy * qz - qw * qx)
        r20 = 2.0 * (qx * qz - qw * qy); r21 = 2.0 * (qy * qz + qw * qx); r22 = 1.0 - 2.0 * (qx * qx + qy * qy)
        vx, vy, vz = vel_world
        u = r00 * vx + r10 * vy + r20 * vz
        v = r01 * vx + r11 * vy + r21 * vz
        w = r02 * vx + r12 * vy + r22 * vz
        p, q, r = omega_body
        self.nu = (u, v, w, p, q, r)

        # Current in body axes and its frame-rotation rate -omega x vc.
        if current_ned is None:
            ur, vr, wr = u, v, w
            cdx = cdy = cdz = 0.0
        else:
            cx, cy, cz = current_ned
            cu = r00 * cx + r10 * cy + r20 * cz
            cv = r01 * cx + r11 * cy + r21 * cz
            cw = r02 * cx + r12 * cy + r22 * cz
            ur, vr, wr = u - cu, v - cv, w - cw
            cdx = -(q * cw - r * cv); cdy = -(r * cu - p * cw); cdz = -(p * cv - q * cu)

        # C_RB(nu) nu about CO: [m w x (v + w x rg); w x Io w + m rg x (w x v)].
        m = self._m
        gx, gy, gz = self._rg
        ax = u + (q * gz - r * gy); ay = v + (r * gx - p * gz); az = w + (p * gy - q * gx)
        c0 = m * (q * az - r * ay); c1 = m * (r * ax - p * az); c2 = m * (p * ay - q * ax)
        I0, I1, I2 = self._Io
        hx = I0[0] * p + I0[1] * q + I0[2] * r
        hy = I1[0] * p + I1[1] * q + I1[2] * r
        hz = I2[0] * p + I2[1] * q + I2[2] * r
        wvx = q * w - r * v; wvy = r * u - p * w; wvz = p * v - q * u
        c3 = (q * hz - r * hy) + m * (gy * wvz - gz * wvy)
        c4 = (r * hx - p * hz) + m * (gz * wvx - gx * wvz)
        c5 = (p * hy - q * hx) + m * (gx * wvy - gy * wvx)

        # C_A(nu_r) nu_r = [w x a1; v_r x a1 + w x a2] with a = M_A nu_r.
        nr = (ur, vr, wr, p, q, r)
        A = self._MA
        if self._diag_added_mass:
            Ad = self._MA_diag
            a0 = Ad[0] * ur; a1 = Ad[1] * vr; a2 = Ad[2] * wr
            a3 = Ad[3] * p; a4 = Ad[4] * q; a5 = Ad[5] * r
        else:
            a0, a1, a2, a3, a4, a5 = [
                A[i][0] * ur + A[i][1] * vr + A[i][2] * wr + A[i][3] * p + A[i][4] * q + A[i][5] * r
                for i in range(6)]
        ca0 = q * a2 - r * a1; ca1 = r * a0 - p * a2; ca2 = p * a1 - q * a0
        ca3 = (vr * a2 - wr * a1) + (q * a5 - r * a4)
        ca4 = (wr * a0 - ur * a2) + (r * a3 - p * a5)
        ca5 = (ur * a1 - vr * a0) + (p * a4 - q * a3)
        if not self._munk:  # drop C_A entries (0,4) a2, (0,5) -a1, (1,5) a0, (2,4) -a0, ...
            ca0 -= a2 * q - a1 * r
            ca1 -= a0 * r
            ca2 += a0 * q
            ca4 -= -a2 * ur + a0 * wr
            ca5 -= a1 * ur - a0 * vr

        # Damping D(nu_r) nu_r.
        if self._has_decay:
            speed = math.sqrt(ur * ur + vr * vr + wr * wr)
            fade = [math.exp(-k * speed) if k else 1.0 for k in self._decay]
        else:
            fade = None
        if self._diag_damping:
            dl, dq = self._dl_diag, self._dq_diag
            if fade is None:  # unrolled: this runs at the physics rate
                d = [(dl[0] + dq[0] * abs(ur)) * ur, (dl[1] + dq[1] * abs(vr)) * vr, (dl[2] + dq[2] * abs(wr)) * wr,
                     (dl[3] + dq[3] * abs(p)) * p, (dl[4] + dq[4] * abs(q)) * q, (dl[5] + dq[5] * abs(r)) * r]
            else:
                d = [(dl[i] * fade[i] + dq[i] * abs(x)) * x for i, x in enumerate(nr)]
        else:
            absn = [abs(x) * x for x in nr]
            d = []
            for i in range(6):
                Li, Qi = self._Dl[i], self._Dq[i]
                lin = sum(Li[j] * nr[j] for j in range(6))
                if fade is not None:
                    lin *= fade[i]
                d.append(lin + sum(Qi[j] * absn[j] for j in range(6)))

        # Restoring g(eta): k = R^T e_z; g = -[(W - B) k; (W rg - B rb) x k].
        if depth_m >= self._emerge_depth:
            wb = self._W_minus_B
            mx, my, mz = self._moment_arm
        else:
            frac = min(max((depth_m + self._bottom_off) / self._hull_h, 0.0), 1.0)
            B = self._B * frac
            wb = self._W - B
            mx = self._rg_W[0] - B * self._rb[0]
            my = self._rg_W[1] - B * self._rb[1]
            mz = self._rg_W[2] - B * self._rb[2]
        g0 = -wb * r20; g1 = -wb * r21; g2 = -wb * r22
        g3 = mz * r21 - my * r22; g4 = mx * r22 - mz * r20; g5 = my * r20 - mx * r21

        t = tau_body
        crb = (c0, c1, c2, c3, c4, c5)
        rhs = [t[0] - c0 - ca0 - d[0] - g0, t[1] - c1 - ca1 - d[1] - g1, t[2] - c2 - ca2 - d[2] - g2,
               t[3] - c3 - ca3 - d[3] - g3, t[4] - c4 - ca4 - d[4] - g4, t[5] - c5 - ca5 - d[5] - g5]
        if cdx or cdy or cdz:
            for i in range(6):
                rhs[i] += A[i][0] * cdx + A[i][1] * cdy + A[i][2] * cdz
        self.rhs = tuple(rhs)

        # Rigid-body wrench about CO, body axes: K rhs + C_RB nu.
        if self._K_sparse:
            Kd = self._K_diag
            f = [Kd[0] * rhs[0] + c0, Kd[1] * rhs[1] + c1, Kd[2] * rhs[2] + c2,
                 Kd[3] * rhs[3] + c3, Kd[4] * rhs[4] + c4, Kd[5] * rhs[5] + c5]
            for i, j, k in self._K_off:
                f[i] += k * rhs[j]
        else:
            K = self._K
            f = [K[i][0] * rhs[0] + K[i][1] * rhs[1] + K[i][2] * rhs[2] + K[i][3] * rhs[3]
                 + K[i][4] * rhs[4] + K[i][5] * rhs[5] + crb[i] for i in range(6)]
        fx, fy, fz, mxo, myo, mzo = f
        # Torque about the CoM: m_co - rg x f.
        mcx = mxo - (gy * fz - gz * fy); mcy = myo - (gz * fx - gx * fz); mcz = mzo - (gx * fy - gy * fx)
        return [r00 * fx + r01 * fy + r02 * fz, r10 * fx + r11 * fy + r12 * fz, r20 * fx + r21 * fy + r22 * fz,
                r00 * mcx + r01 * mcy + r02 * mcz, r10 * mcx + r11 * mcy + r12 * mcz,
                r20 * mcx + r21 * mcy + r22 * mcz]
