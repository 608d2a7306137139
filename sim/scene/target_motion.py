"""Kinematics of moving targets (pure numpy): a diver or small vehicle, and its bubble plumes.

:class:`ManoeuvreTrajectory` follows paper 004 eq. (6) (docs/references.md [P004]):
``n' = u cos(psi)``, ``e' = u sin(psi)``, ``d' = w``, ``psi' = r`` with surge ``u``, heave
``w``, course ``psi`` and course rate ``r`` held constant over manoeuvres of random length
(drawn once per run from the mover's generator), so the pose at any time is exact (circular
arcs), whatever the step it is sampled at. :class:`BubblePlumes` releases a cluster of
scatterers at the regulator every breath; each rises at its own speed and spreads
horizontally, the cluster is carried by the water (:class:`WaterDrift`) and briefly by the
diver's wake, and is gone after its lifetime or at the surface.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from scenarios.config.movers import BubbleConfig, MoverConfig

FloatArray = NDArray[np.float64]
PARKED_NED = np.array([0.0, 0.0, -1000.0])  # where a bubble that is not in the water waits (above the surface)


def _arc(u: FloatArray, r: FloatArray, c0: FloatArray, tau: FloatArray) -> tuple[FloatArray, FloatArray]:
    """North and east displacement after ``tau`` s at surge ``u`` (m/s), course rate ``r``
    (rad/s) from course ``c0`` (rad); the straight line where ``|r|`` < 1e-9."""
    straight = np.abs(r) < 1e-9
    rs = np.where(straight, 1.0, r)
    c1 = c0 + r * tau
    dn = np.where(straight, u * tau * np.cos(c0), u / rs * (np.sin(c1) - np.sin(c0)))
    de = np.where(straight, u * tau * np.sin(c0), u / rs * (np.cos(c0) - np.cos(c1)))
    return dn, de


class ManoeuvreTrajectory:
    """Seeded piecewise-constant-manoeuvre trajectory of one mover over ``[0, duration_s]``.

    Args:
        cfg: the mover's config.
        rng: its own generator (``sim.rng.component_rng(seed, "mover:<name>")``).
        duration_s: time span to draw manoeuvres for (the pose is held after it), s.

    Attributes:
        t0_s: (K,) start time of each manoeuvre; ``pos0_ned`` (K, 3), ``course0_rad`` (K,),
        ``course_rate_radps``, ``surge_mps``, ``heave_mps`` (K,) its start state and controls.
    """

    def __init__(self, cfg: MoverConfig, rng: np.random.Generator, duration_s: float) -> None:
        self.cfg = cfg
        lo, hi = cfg.depth_band_m
        centre = np.asarray(cfg.leash_center_ne_m if cfg.leash_center_ne_m is not None else cfg.initial_pos_ned[:2],
                            dtype=float)
        p = np.asarray(cfg.initial_pos_ned, dtype=float).copy()
        c = math.radians(cfg.initial_course_deg)
        t = 0.0
        rows = []
        while t <= duration_s:
            dur = max(float(rng.exponential(cfg.manoeuvre_mean_s)), 0.5)
            u = max(float(cfg.surge_mps + cfg.surge_sigma_mps * rng.standard_normal()), 0.0)
            r = math.radians(cfg.course_rate_sigma_dps) * float(rng.standard_normal())
            w = cfg.heave_sigma_mps * float(rng.standard_normal())
            if np.hypot(*(p[:2] - centre)) > cfg.leash_radius_m:  # turn back towards the centre
                dur = max(dur, 3.0)
                to_centre = math.atan2(centre[1] - p[1], centre[0] - p[0])
                r = math.remainder(to_centre - c, 2 * math.pi) / dur
            if p[2] + w * dur > hi:
                w = (hi - p[2]) / dur
            elif p[2] + w * dur < lo:
                w = (lo - p[2]) / dur
            rows.append((t, *p, c, r, u, w))
            dn, de = _arc(np.array(u), np.array(r), np.array(c), np.array(dur))
            p = p + np.array([float(dn), float(de), w * dur])
            c = c + r * dur
            t += dur
        a = np.array(rows, dtype=float)
        self.t0_s = a[:, 0]
        self.pos0_ned = a[:, 1:4]
        self.course0_rad = a[:, 4]
        self.course_rate_radps = a[:, 5]
        self.surge_mps = a[:, 6]
        self.heave_mps = a[:, 7]
        self._t_end = float(t)

    def state_at(self, t_s: float | FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        """Pose and controls at ``t_s`` (() or (N,)): position (..., 3) NED m, course (rad,
        unwrapped), course rate (rad/s), surge (m/s), heave (m/s)."""
        t = np.asarray(t_s, dtype=float)
        k = np.clip(np.searchsorted(self.t0_s, t, side="right") - 1, 0, len(self.t0_s) - 1)
        tau = np.clip(t - self.t0_s[k], 0.0, None)
        u, r, w, c0 = self.surge_mps[k], self.course_rate_radps[k], self.heave_mps[k], self.course0_rad[k]
        dn, de = _arc(u, r, c0, tau)
        pos = self.pos0_ned[k] + np.stack([dn, de, w * tau], axis=-1)
        return pos, c0 + r * tau, r, u, w

    def pose_at(self, t_s: float) -> tuple[FloatArray, float]:
        """(3,) NED position (m) and course (rad) at ``t_s``."""
        pos, course, *_ = self.state_at(t_s)
        return pos, float(course)


class WaterDrift:
    """Displacement of a water parcel by a spatially uniform current since t = 0 (NED, m).

    ``D(t) = mean t + integral_0^t g(s) ds``: the mean part is exact; the time-varying part
    ``g`` (the Gauss-Markov part of :class:`sim.dynamics.current.OceanCurrent`) is integrated from the
    values :meth:`record` is given, each held until the next (as the physics holds the
    current over a step). A record at an earlier time than the last one starts a new history
    (the clock was reset).

    Args:
        mean_ned_mps: (3,) the current's constant part, m/s.
    """

    def __init__(self, mean_ned_mps=(0.0, 0.0, 0.0)) -> None:
        self.mean_ned_mps = np.asarray(mean_ned_mps, dtype=float).reshape(3)
        self._n = 0
        self._t = np.empty(1024)  # record times
        self._d = np.empty((1024, 3))  # integral of g up to _t[i]
        self._g = np.empty((1024, 3))  # g held from _t[i]
        #: bumped whenever recorded history is dropped (a clock reset): cached displacements are stale
        self.generation = 0

    def record(self, t_s: float, velocity_ned_mps) -> None:
        """The current (3,) m/s in force from ``t_s`` on."""
        g = np.asarray(velocity_ned_mps, dtype=float) - self.mean_ned_mps
        n = self._n
        if n and t_s < self._t[n - 1] - 1e-12:
            n = 0  # the clock went back: a new history
            self.generation += 1
        if n == 0:
            d = np.zeros(3)  # before the first record the varying part is taken as zero
        else:
            d = self._d[n - 1] + self._g[n - 1] * (t_s - self._t[n - 1])
            if t_s <= self._t[n - 1] + 1e-12:  # same instant: replace
                n -= 1
        if n == len(self._t):
            self._t = np.resize(self._t, 2 * n)
            self._d = np.resize(self._d, (2 * n, 3))
            self._g = np.resize(self._g, (2 * n, 3))
        self._t[n], self._d[n], self._g[n] = t_s, d, g
        self._n = n + 1

    @property
    def history_end_s(self) -> float:
        """Time of the last record (-inf: none); the displacement up to it is final."""
        return float(self._t[self._n - 1]) if self._n else -math.inf

    def displacement_at(self, t_s: float | FloatArray) -> FloatArray:
        """(..., 3) water displacement since t = 0 at ``t_s`` (() or (N,)), m."""
        t = np.asarray(t_s, dtype=float)
        out = t[..., None] * self.mean_ned_mps
        n = self._n
        if n == 0:
            return out
        if t.ndim == 0 and t_s >= self._t[n - 1]:  # now (the physics' query): the last record holds
            return out + self._d[n - 1] + self._g[n - 1] * (t_s - self._t[n - 1])
        ts = self._t[:n]
        k = np.clip(np.searchsorted(ts, t, side="right") - 1, 0, n - 1)
        return out + self._d[k] + self._g[k] * np.clip(t - ts[k], 0.0, None)[..., None]


MIN_BREATH_FRACTION, MAX_BREATH_FRACTION = 0.6, 1.4  # breath intervals, x breath_period_s


def plume_slots(cfg: BubbleConfig) -> int:
    """Most breaths of a plume in the water at once (each interval is at least 0.6 x the period)."""
    return int(math.ceil(cfg.lifetime_s / (MIN_BREATH_FRACTION * cfg.breath_period_s))) + 1


class BubblePlumes:
    """Bubble scatterers of one diver: :func:`plume_slots` clusters of ``cfg.per_breath`` bubbles recycled.

    A breath released at ``t_k`` from the regulator ``r_k`` (``cfg.release_offset_body_m``
    turned by the diver's course, plus a 5 cm scatter per bubble) puts bubble ``j`` at age
    ``a = t - t_k`` at

        ``p = r_k + s_j + v_j a + f v_rel tau (1 - exp(-a / tau)) + D(t) - D(t_k)``

    with ``v_j`` its own velocity (rise ``-w_j`` down, ``w_j ~ N(rise, rise_sigma)`` clipped
    at 0.05 m/s; horizontal spread ``N(0, dispersion^2)`` per axis), ``v_rel`` the diver's
    horizontal velocity through the water at release (its ground velocity less the mean
    current), ``f`` and ``tau`` the wake's share and decay, and ``D`` the water's
    displacement (:class:`WaterDrift`). A bubble is gone after ``cfg.lifetime_s`` or within
    5 cm of the surface.

    Args:
        cfg: the plume config.
        source: the diver's trajectory.
        rng: the plume's own generator.
        duration_s: time span to draw releases for, s.
        drift: the water's displacement (None: still water).
    """

    def __init__(self, cfg: BubbleConfig, source: ManoeuvreTrajectory, rng: np.random.Generator,
                 duration_s: float, drift: WaterDrift | None = None) -> None:
        self.cfg = cfg
        self.drift = drift if drift is not None else WaterDrift()
        self.n_slots = plume_slots(cfg)
        self.n_bubbles = self.n_slots * cfg.per_breath
        self.phase_s = float(rng.uniform(0.0, cfg.breath_period_s))
        n_rel = int(math.ceil((duration_s + cfg.breath_period_s) / (MIN_BREATH_FRACTION * cfg.breath_period_s))) + 1
        gaps = np.clip(cfg.breath_period_s + cfg.breath_jitter_s * rng.standard_normal(n_rel - 1),
                       MIN_BREATH_FRACTION * cfg.breath_period_s, MAX_BREATH_FRACTION * cfg.breath_period_s)
        self.release_t_s = self.phase_s + np.concatenate([[0.0], np.cumsum(gaps)])
        pos, course, _, surge, _ = source.state_at(self.release_t_s)
        off = np.asarray(cfg.release_offset_body_m, dtype=float)
        c, s = np.cos(course), np.sin(course)
        #: (n_rel, 3) regulator position at each release, NED m
        self.regulator_ned = pos + np.stack([c * off[0] - s * off[1], s * off[0] + c * off[1],
                                             np.full_like(course, off[2])], axis=-1)
        m = cfg.per_breath
        self.start_ned = self.regulator_ned[:, None, :] + 0.05 * rng.standard_normal((n_rel, m, 3))
        vel = np.empty((n_rel, m, 3))
        vel[..., :2] = cfg.dispersion_mps * rng.standard_normal((n_rel, m, 2))
        vel[..., 2] = -np.clip(cfg.rise_speed_mps + cfg.rise_speed_sigma_mps * rng.standard_normal((n_rel, m)),
                               0.05, None)
        self.vel_ned_mps = vel
        v_rel = np.stack([surge * c, surge * s], axis=-1) - self.drift.mean_ned_mps[:2]
        #: (n_rel, 3) how far the wake carries each breath in the end, m
        self.wake_ned_m = np.concatenate([cfg.wake_fraction * cfg.wake_decay_s * v_rel, np.zeros((n_rel, 1))], axis=1)
        self._d_release = np.full((n_rel, 3), np.nan)  # water displacement at each release, once known
        self._d_generation = self.drift.generation

    def _release_displacement(self, k: NDArray[np.intp]) -> FloatArray:
        """(K, 3) water displacement at releases ``k``; those at or before the drift's last
        record are final (until the clock is reset) and cached."""
        if self._d_generation != self.drift.generation:
            self._d_release[:] = np.nan
            self._d_generation = self.drift.generation
        d = self._d_release[k]
        new = np.isnan(d[:, 0])
        if new.any():
            d[new] = self.drift.displacement_at(self.release_t_s[k[new]])
            final = new & (self.release_t_s[k] <= self.drift.history_end_s)
            self._d_release[k[final]] = d[final]
        return d

    def breaths_at(self, t_s: float) -> tuple[NDArray[np.intp], FloatArray, FloatArray, NDArray[np.bool_]]:
        """The breaths in the water at ``t_s``: release indices (K,), ages (K,) s, bubble
        positions (K, per_breath, 3) NED m and which bubbles are below the surface (K, per_breath)."""
        cfg = self.cfg
        hi = int(np.searchsorted(self.release_t_s, t_s, side="right"))
        lo = int(np.searchsorted(self.release_t_s, t_s - cfg.lifetime_s, side="right"))
        k = np.arange(lo, max(hi, lo))
        age = t_s - self.release_t_s[k]
        water = self.drift.displacement_at(t_s) - self._release_displacement(k)
        shift = water + self.wake_ned_m[k] * (-np.expm1(-age / cfg.wake_decay_s))[:, None]
        p = self.start_ned[k] + age[:, None, None] * self.vel_ned_mps[k] + shift[:, None, :]
        return k, age, p, p[..., 2] > 0.05

    def positions_at(self, t_s: float) -> tuple[FloatArray, NDArray[np.bool_]]:
        """(n_bubbles, 3) NED positions (m) at ``t_s`` and which are in the water (the others
        at :data:`PARKED_NED`); breath ``k`` fills slot ``k mod n_slots``."""
        m = self.cfg.per_breath
        out = np.broadcast_to(PARKED_NED, (self.n_bubbles, 3)).copy()
        alive = np.zeros(self.n_bubbles, dtype=bool)
        k, _, p, ok = self.breaths_at(t_s)
        if len(k):
            idx = (k % self.n_slots)[:, None] * m + np.arange(m)[None, :]
            out[idx[ok]] = p[ok]
            alive[idx[ok]] = True
        return out, alive
