"""Kinematics of moving targets (pure numpy): a diver or small vehicle, and its bubble plumes.

:class:`ManoeuvreTrajectory` follows paper 004 eq. (6) (docs/references.md [P004]):
``n' = u cos(psi)``, ``e' = u sin(psi)``, ``d' = w``, ``psi' = r`` with surge ``u``, heave
``w``, course ``psi`` and course rate ``r`` held constant over manoeuvres of random length
(drawn once per run from the mover's generator), so the pose at any time is exact (circular
arcs), whatever the step it is sampled at. :class:`BubblePlumes` releases a cluster of
scatterers at the regulator every breath; each rises at its own speed and drifts
horizontally, and is gone after its lifetime or at the surface.
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


class BubblePlumes:
    """Bubble scatterers of one diver: ``n_slots`` clusters of ``cfg.per_breath`` bubbles recycled.

    Args:
        cfg: the plume config.
        source: the diver's trajectory (release point: ``cfg.release_offset_body_m`` rotated by its course).
        rng: the plume's own generator.
        duration_s: time span to draw releases for, s.
    """

    def __init__(self, cfg: BubbleConfig, source: ManoeuvreTrajectory, rng: np.random.Generator,
                 duration_s: float) -> None:
        self.cfg = cfg
        self.n_slots = int(math.ceil(cfg.lifetime_s / cfg.breath_period_s))
        self.n_bubbles = self.n_slots * cfg.per_breath
        self.phase_s = float(rng.uniform(0.0, cfg.breath_period_s))
        n_rel = int(math.ceil((duration_s + cfg.breath_period_s) / cfg.breath_period_s)) + 1
        self.release_t_s = self.phase_s + cfg.breath_period_s * np.arange(n_rel)
        pos, course, *_ = source.state_at(self.release_t_s)
        off = np.asarray(cfg.release_offset_body_m, dtype=float)
        reg = pos + np.stack([np.cos(course) * off[0] - np.sin(course) * off[1],
                              np.sin(course) * off[0] + np.cos(course) * off[1],
                              np.full_like(course, off[2])], axis=-1)
        m = cfg.per_breath
        self.start_ned = reg[:, None, :] + 0.05 * rng.standard_normal((n_rel, m, 3))
        vel = np.empty((n_rel, m, 3))
        vel[..., :2] = cfg.dispersion_mps * rng.standard_normal((n_rel, m, 2))
        vel[..., 2] = -np.clip(cfg.rise_speed_mps + cfg.rise_speed_sigma_mps * rng.standard_normal((n_rel, m)),
                               0.05, None)
        self.vel_ned_mps = vel

    def positions_at(self, t_s: float) -> tuple[FloatArray, NDArray[np.bool_]]:
        """(n_bubbles, 3) NED positions (m) at ``t_s`` and which are in the water (the others
        at :data:`PARKED_NED`)."""
        cfg, m = self.cfg, self.cfg.per_breath
        out = np.broadcast_to(PARKED_NED, (self.n_bubbles, 3)).copy()
        alive = np.zeros(self.n_bubbles, dtype=bool)
        k_now = math.floor((t_s - self.phase_s) / cfg.breath_period_s + 1e-12)
        for s in range(self.n_slots):
            k = k_now - ((k_now - s) % self.n_slots)
            if k < 0 or k >= len(self.release_t_s):
                continue
            age = t_s - self.release_t_s[k]
            if not 0.0 <= age < cfg.lifetime_s:
                continue
            p = self.start_ned[k] + age * self.vel_ned_mps[k]
            ok = p[:, 2] > 0.05
            sl = slice(s * m, (s + 1) * m)
            out[sl][ok] = p[ok]
            alive[sl] = ok
        return out, alive
