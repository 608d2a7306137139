"""Particle sum-product (SPA) mapping of seabed objects with the vehicle state (paper 003).

Gaglione, Soldi, Braca, "Autonomous mapping of underwater objects with the sum-product
algorithm under unknown AUV position", JAIF 2023, Section IV (messages) and V (set-up).

Beliefs:
* vehicle state ``s = [north, east, v_north, v_east, turn rate]`` (NED, m, m/s, rad/s): N
  particles, propagated at the INS rate by the nearly-constant-turn model
  (:mod:`autonomy.mapping.auv_motion`, drawn from the locally optimal proposal given each
  INS output, :func:`~autonomy.mapping.auv_motion.nct_predict_ins_proposal`) and weighted by the INS output
  ``g = [north, east, heading] + v`` with ``var v = diag(s_p^2, s_p^2, s_h^2)``,
  ``s_p^2 = (3 varsigma_p)^2 tau^3 / 3``, ``s_h^2 = (3 varsigma_h)^2 tau^2`` (tau hours; paper eq.
  after 30), floored by ``nav_floor_*`` so the first seconds do not degenerate the particles;
* each potential object (PO) k: existence ``r_k``, N position particles (NED north, east) and
  per-particle class weights ``W_k[i, c]`` (joint position-class belief, sum 1).

At each tile pair (measurements: positions ``ell`` in the vehicle frame, along-track forward
and across-track starboard, m, and the ATR probability ``pi`` of class 1), the legacy POs'
association weights ``beta_k(m)`` (IV-C), new-PO weights
``xi_m = 1 + mu_N / mu_0 sum_c f_N(c) f(pi_m | c)`` (eq. 15: uniform new-object prior over the
tile, uniform clutter ``pi``), association by loopy BP
(:mod:`autonomy.mapping.data_association`), then the messages from the legacy POs to the
vehicle state (``spa`` mode), the PO beliefs from the *extrinsic* vehicle belief (every message
but the PO's own, IV-D), new POs from the measurements mapped through the updated vehicle
belief, pruning at ``P_th`` and confirmation at ``E_th``. The detection probability is
averaged over the vehicle (and PO) uncertainty (a hard tile edge at the mean state turns
objects near a tile boundary into misses, then into new duplicate POs); detection terms carry
no in-tile factor (a detection lies in the tile). Resampled PO particles are roughened
(Gordon, Salmond and Smith 1993: jitter of standard deviation ``K E N^(-1/d)``, E the particle
range per dimension, here the 1-99 percentile range so that a few outliers do not inflate it);
the vehicle particles are not (a velocity jitter is a heading jitter).

Implementation choice (documented deviation): the paper's particle messages are quadratic in
N (every vehicle particle against every PO particle). Here every cross integral uses a
Gaussian summary of the *other* belief (its mean and covariance; the heading spread enters
linearised): the association weights and PO updates summarise the vehicle belief, the
messages to the vehicle summarise each PO, so a step is linear in N. (Pairing the particles
at random instead starves ``beta`` once the vehicle spread exceeds the measurement noise:
with 300 pairs, a 20 m spread and sigma 1 m almost no pair lands near the detection.)

Modes (paper 003's baselines from the same code): ``spa``; ``clairvoyant`` (true state given
by :meth:`SpaMapper.set_true_state`); ``ins_plain`` (the INS output as the state);
``ins_filter`` (particle filter on the INS only; objects mapped from its mean).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import betaln, ndtr

from autonomy.mapping.auv_motion import heading_rad, ins_proposal_columns, wrap_angle
from autonomy.mapping.config import SpaMapperConfig
from autonomy.mapping.data_association import loopy_bp

FloatArray = NDArray[np.float64]
S_PER_H = 3600.0


def beta_pdf(x: ArrayLike, a: float, b: float) -> FloatArray:
    """Beta(a, b) density at x (clipped into (1e-9, 1 - 1e-9))."""
    x = np.clip(np.asarray(x, dtype=float), 1e-9, 1.0 - 1e-9)
    return np.exp((a - 1.0) * np.log(x) + (b - 1.0) * np.log1p(-x) - betaln(a, b))


def systematic_resample(weights: FloatArray, rng: np.random.Generator) -> NDArray[np.intp]:
    """Systematic resampling indices (N,) of normalised weights (N,)."""
    n = len(weights)
    c = np.cumsum(weights)
    c[-1] = 1.0
    return np.searchsorted(c, (rng.random() + np.arange(n)) / n).astype(np.intp)


def rotate_to_local(d_ned: FloatArray, psi: FloatArray) -> FloatArray:
    """NED offsets (..., 2) -> vehicle frame (along forward, across starboard) at heading psi (...)."""
    c, s = np.cos(psi), np.sin(psi)
    return np.stack([c * d_ned[..., 0] + s * d_ned[..., 1], -s * d_ned[..., 0] + c * d_ned[..., 1]], axis=-1)


def rotate_to_ned(ell: FloatArray, psi: FloatArray) -> FloatArray:
    """Vehicle-frame offsets (..., 2) -> NED at heading psi (...)."""
    c, s = np.cos(psi), np.sin(psi)
    return np.stack([c * ell[..., 0] - s * ell[..., 1], s * ell[..., 0] + c * ell[..., 1]], axis=-1)


@dataclass(frozen=True)
class MapEstimate:
    """Confirmed objects: ``pos_ned`` (J, 2) m, ``class_index`` (J,) (0: class 1 = mine-like),
    ``existence`` (J,)."""

    pos_ned: FloatArray
    class_index: NDArray[np.intp]
    existence: FloatArray


class SpaMapper:
    """Particle SPA mapper (see the module docstring).

    Args:
        cfg: parameters and mode.
        initial_state: (5,) ``[north, east, v_north, v_east, turn rate]`` at the start (known).
        rng: the mapper's generator.
        initial_std: (5,) spread of the initial vehicle particles.
    """

    def __init__(self, cfg: SpaMapperConfig, initial_state: ArrayLike, rng: np.random.Generator,
                 initial_std: ArrayLike = (0.5, 0.5, 0.05, 0.05, 0.001)) -> None:
        self.cfg = cfg
        self.rng = rng
        n = cfg.n_particles
        s0 = np.asarray(initial_state, dtype=float).reshape(5)
        self.S = s0 + rng.standard_normal((n, 5)) * np.asarray(initial_std, dtype=float)
        self.w = np.full(n, 1.0 / n)
        self.point_state = s0.copy()  # clairvoyant / ins_plain
        self.r = np.zeros(0)
        self.X = np.zeros((0, n, 2))
        self.W = np.zeros((0, n, cfg.n_classes))
        self._po_stats = np.zeros((0, 3))  # per PO: position mean (2) and total variance, m, m^2
        self.t_s = 0.0
        self.tile_area_m2 = 2.0 * cfg.tile_length_m * cfg.tile_width_m
        self.last_association: object = None

    # -- vehicle state --------------------------------------------------------------------------
    def nav_update(self, t_s: float, g: ArrayLike) -> None:
        """Advance to ``t_s`` (s since the start) and take one INS output ``g`` = (north m, east m,
        heading rad). ``clairvoyant`` ignores it; ``ins_plain`` takes it as the state."""
        self.nav_updates(np.array([t_s], dtype=float), np.asarray(g, dtype=float).reshape(1, 3))

    def nav_updates(self, t_s: ArrayLike, g: ArrayLike) -> None:
        """Take INS outputs ``g`` (T, 3) (north m, east m, heading rad) at times ``t_s`` (T,) (s
        since the start, non-decreasing, after the last one taken), one after the other: the
        same filter as T calls of :meth:`nav_update`, run as one loop (between tiles the vehicle
        belief is only propagated and weighted by the INS).

        Per output: the particles are drawn from the locally optimal proposal
        (:func:`~autonomy.mapping.auv_motion.ins_proposal_columns`) and weighted by its
        predictive likelihood; they are resampled when the effective sample size falls below N/2.

        Raises:
            ValueError: shapes differ.
        """
        t = np.asarray(t_s, dtype=float).reshape(-1)
        g = np.asarray(g, dtype=float).reshape(-1, 3)
        if len(t) != len(g):
            raise ValueError(f"nav_updates: {len(t)} times but {len(g)} INS outputs")
        if len(t) == 0:
            return
        cfg = self.cfg
        dts = np.diff(t, prepend=self.t_s)
        self.t_s = float(t[-1])
        if cfg.mode == "clairvoyant":
            return
        if cfg.mode == "ins_plain":  # only the last output counts; the speed is carried over
            speed = float(np.hypot(self.point_state[2], self.point_state[3])) or 1.0
            self.point_state = np.array([g[-1, 0], g[-1, 1], speed * np.cos(g[-1, 2]), speed * np.sin(g[-1, 2]), 0.0])
            return
        tau = t / S_PER_H
        var_p = np.maximum(cfg.nav_floor_pos_m ** 2, (3.0 * cfg.varsigma_p) ** 2 * tau ** 3 / 3.0)
        var_h = np.maximum(np.deg2rad(cfg.nav_floor_heading_deg) ** 2,
                           (3.0 * np.deg2rad(cfg.varsigma_h_deg_per_sqrt_h)) ** 2 * tau ** 2)
        sigma_ang = float(np.deg2rad(cfg.sigma_ang_degps2))
        cols = self.S.T  # (5, N) by component
        w = self.w
        half_n = 0.5 * len(w)
        for k in range(len(t)):
            if dts[k] > 0.0:
                cols, logw = ins_proposal_columns(cols, float(dts[k]), cfg.sigma_lin_mps2, sigma_ang, g[k],
                                                  float(var_p[k]), float(var_h[k]), self.rng)
            else:
                dpsi = wrap_angle(np.arctan2(cols[3], cols[2]) - g[k, 2])
                logw = -0.5 * (((cols[0] - g[k, 0]) ** 2 + (cols[1] - g[k, 1]) ** 2) / var_p[k]
                               + dpsi ** 2 / var_h[k])
            logw += np.log(np.maximum(w, 1e-300))
            logw -= logw.max()
            w = np.exp(logw, out=logw)
            w /= w.sum()
            if 1.0 / np.dot(w, w) < half_n:
                cols = cols[:, systematic_resample(w, self.rng)]
                w = np.full(len(w), 1.0 / len(w))
        self.S, self.w = cols.T, w

    def set_true_state(self, state: ArrayLike) -> None:
        """The true state (5,) (``clairvoyant`` mode only uses it)."""
        if self.cfg.mode == "clairvoyant":
            self.point_state = np.asarray(state, dtype=float).reshape(5).copy()

    def _resample_vehicle(self) -> None:
        """Resample the vehicle particles to equal weights. Not roughened: an isotropic jitter
        of the velocity is a heading jitter (0.1 m/s at 1.5 m/s is 4 deg, 5 m at 70 m abeam),
        and the next second's process noise restores the diversity anyway."""
        n = len(self.w)
        self.S = self.S[systematic_resample(self.w, self.rng)]
        self.w = np.full(n, 1.0 / n)

    def _roughening(self, particles: FloatArray) -> FloatArray:
        n, d = particles.shape
        lo, hi = np.percentile(particles, [1.0, 99.0], axis=0)
        span = hi - lo
        return self.rng.standard_normal(particles.shape) * (self.cfg.roughening_k * span * n ** (-1.0 / d))

    def vehicle_estimate(self) -> FloatArray:
        """(5,) state estimate (weighted mean; the given state in point modes)."""
        if self.cfg.mode in ("clairvoyant", "ins_plain"):
            return self.point_state.copy()
        return self.w @ self.S

    def _object_frame_particles(self) -> FloatArray:
        """(N, 5) vehicle states the objects are mapped from: the particles (``spa``) or N copies
        of the estimate (the baselines map from a point)."""
        n = self.cfg.n_particles
        if self.cfg.mode == "spa":
            return self.S
        return np.repeat(self.vehicle_estimate()[None, :], n, axis=0)

    # -- tiles ----------------------------------------------------------------------------------
    def _in_tile(self, ell: FloatArray) -> NDArray[np.bool_]:
        cfg = self.cfg
        a = np.abs(ell[..., 1])
        return ((ell[..., 0] >= -cfg.tile_length_m) & (ell[..., 0] <= 0.0) & (a >= cfg.tile_near_m)
                & (a <= cfg.tile_near_m + cfg.tile_width_m))

    def tile_update(self, ell_m: ArrayLike, pi1: ArrayLike) -> None:
        """Process one tile pair's detections.

        Args:
            ell_m: (M, 2) detection positions in the vehicle frame (along forward, across
                starboard), m.
            pi1: (M,) ATR probability of class 1 (mine-like).

        Raises:
            ValueError: shapes differ or values are not finite.
        """
        cfg = self.cfg
        ell = np.asarray(ell_m, dtype=float).reshape(-1, 2)
        p1 = np.asarray(pi1, dtype=float).reshape(-1)
        if len(p1) != len(ell) or not (np.all(np.isfinite(ell)) and np.all(np.isfinite(p1))):
            raise ValueError("tile_update: ell_m (M, 2) and pi1 (M,) must be finite and of one length")
        n, m_n = cfg.n_particles, len(ell)
        if cfg.mode in ("spa", "ins_filter"):
            self._resample_vehicle()
        f_pi = np.stack([beta_pdf(p1, *cfg.class_beta_1), beta_pdf(p1, *cfg.class_beta_2)], axis=1)  # (M, C)
        ratio = self.tile_area_m2 / cfg.clutter_mean  # 1 / (mu_0 f_FA(ell)) with uniform pi
        xi = 1.0 + cfg.new_object_mean / cfg.clutter_mean * f_pi.mean(axis=1)  # eq. 15: mu_N counts detected objects
        veh = self._object_frame_particles()
        rel = self._relevant(veh)
        k_r = len(rel)
        # PO measurement terms under the equally weighted vehicle belief: the association weights
        # use them, and so does the PO update of the point modes (there the belief is the same)
        terms = None
        if k_r and (m_n or cfg.mode != "spa"):
            terms = self._po_likelihoods(self.X[rel], self._uniform_vehicle_summary(veh), ell)
        if k_r and m_n:
            beta = self.association_weights(rel, veh, ell, f_pi, terms)
            bp = loopy_bp(beta, xi, tol=cfg.bp_tol)
            nu, phi_sum = bp.nu, bp.phi.sum(axis=0)
            self.last_association = bp
        else:
            nu, phi_sum = np.ones((k_r, m_n)), np.zeros(m_n)
        ext_logw = np.zeros((k_r, n))  # extrinsic vehicle log-weights seen by each legacy PO
        logw_post = None
        if cfg.mode == "spa" and k_r:
            log_gamma = self._po_to_vehicle_messages(rel, ell, f_pi, nu, ratio)  # (Kr, N)
            logw_post = log_gamma.sum(axis=0)
            # message to PO k: the vehicle belief times every message but its own (paper IV-D)
            ext_logw = logw_post[None, :] - log_gamma
        if k_r:
            self._update_legacy(rel, veh, ell, f_pi, nu, ratio, ext_logw, terms)
        if logw_post is not None:
            lw = np.exp(logw_post - logw_post.max())
            self.w = lw / lw.sum()
            self._resample_vehicle()
            veh = self._object_frame_particles()
        self._add_new(veh, ell, f_pi, xi, phi_sum)
        self._drop(self.r < cfg.prune_threshold)
        if cfg.merge_gate > 0.0:
            self._merge_coincident()

    def _drop(self, gone: NDArray[np.bool_]) -> None:
        if not gone.any():
            return
        keep = ~gone
        if len(self._po_stats) == len(keep):
            self._po_stats = self._po_stats[keep]
        self.r, self.X, self.W = self.r[keep], self.X[keep], self.W[keep]

    def _merge_coincident(self) -> None:
        """Merge POs whose position beliefs coincide (documented deviation from paper 003).

        The BP keeps one PO per measurement but nothing removes a second PO of the same object:
        once two POs of one object are both near existence 1 (each tile one takes the detection,
        the other a miss), a miss divides the odds only by about five, and the stationary model
        has no survival probability, so both stay confirmed for the rest of the survey and the
        duplicate counts as a false object. Two POs with existence above 0.05 whose means are
        closer than ``sqrt(merge_gate (var_1 + var_2 + 2 sigma^2))`` (total position variances)
        become the one with the higher existence, with existence ``1 - (1 - r_1)(1 - r_2)``.
        """
        if len(self._po_stats) != len(self.r):
            self._po_stats = self._summarise_pos(self.X)
        cand = np.flatnonzero(self.r > 0.05)
        if len(cand) < 2:
            return
        mu, var = self._po_stats[cand, :2], self._po_stats[cand, 2]
        d2 = ((mu[:, None] - mu[None]) ** 2).sum(-1)
        gate = self.cfg.merge_gate * (var[:, None] + var[None] + 2.0 * self.cfg.sigma_meas_m ** 2)
        gone = np.zeros(len(self.r), dtype=bool)
        for i, j in zip(*np.nonzero(np.triu(d2 < gate, 1))):
            a, b = cand[i], cand[j]
            if gone[a] or gone[b]:
                continue
            keep, lose = (a, b) if self.r[a] >= self.r[b] else (b, a)
            self.r[keep] = 1.0 - (1.0 - self.r[keep]) * (1.0 - self.r[lose])
            gone[lose] = True
        if gone.any():
            self._drop(gone)

    def association_weights(self, rel: NDArray[np.intp], veh: FloatArray, ell: FloatArray, f_pi: FloatArray,
                            terms: tuple[FloatArray, FloatArray] | None = None) -> FloatArray:
        """Association weights ``beta`` (Kr, M + 1) of POs ``rel`` (paper 003, IV-C, message
        ``zeta_{q_k -> a_k}``): column 0 ``(1 - r) + r E[1 - P_d]``, column m
        ``r pd E[in tile f(ell_m | x, s) f(pi_m | c)] / (mu_0 f_FA(z_m))``; the expectation over
        the vehicle belief ``veh`` (N, 5), equally weighted, is taken in closed form over its
        Gaussian summary (:meth:`_vehicle_summaries`), the one over the PO over its particles.

        Args:
            rel: (Kr,) PO indices; veh: (N, 5) vehicle states; ell: (M, 2) detections (vehicle
                frame, m); f_pi: (M, C) class likelihoods ``f(pi_m | c)``; terms: the POs'
                :meth:`_po_likelihoods` under that belief when already computed.
        """
        cfg = self.cfg
        ratio = self.tile_area_m2 / cfg.clutter_mean
        if terms is None:
            terms = self._po_likelihoods(self.X[rel], self._uniform_vehicle_summary(veh), ell)
        lik, inside = terms  # (Kr, N, M), (Kr, N)
        cls = np.einsum("kic,mc->kim", self.W[rel], f_pi)  # (Kr, N, M)
        rr = self.r[rel]
        beta = np.empty((len(rel), len(ell) + 1))
        # a detection lies in the tile: its term needs no in-tile factor (f(ell | x, s) is
        # negligible where x is outside); the miss term takes E_s[P_d]
        beta[:, 1:] = rr[:, None] * cfg.pd * ratio * np.einsum("kim->km", lik * cls)
        miss = (self.W[rel].sum(-1) * (1.0 - cfg.pd * inside)).sum(1)
        beta[:, 0] = (1.0 - rr) + rr * miss
        return beta

    def _uniform_vehicle_summary(self, veh: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """:meth:`_vehicle_summaries` of the equally weighted particles ``veh`` (N, 5) (B = 1)."""
        return self._vehicle_summaries(veh, np.full((1, len(veh)), 1.0 / len(veh)))

    def _vehicle_summaries(self, veh: FloatArray, w: FloatArray
                           ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Gaussian summaries of the vehicle particles ``veh`` (N, 5) under B weightings ``w``
        (B, N), rows summing to 1: ``(pos mean (B, 2), heading mean (B,), pos covariance
        (B, 2, 2), heading variance (B,))`` (NED, m, rad); the point modes have no spread."""
        # einsum, not matmul: these thin products would go to a multi-threaded BLAS, whose
        # threads cost more than the arithmetic (and oversubscribe the cores of parallel runs)
        psis = heading_rad(veh)
        p_mean = np.einsum("bn,nd->bd", w, veh[:, :2])
        psi_mean = np.arctan2(np.einsum("bn,n->b", w, np.sin(psis)), np.einsum("bn,n->b", w, np.cos(psis)))
        if self.cfg.mode != "spa":
            return p_mean, psi_mean, np.zeros((len(w), 2, 2)), np.zeros(len(w))
        dp = veh[None, :, :2] - p_mean[:, None, :]  # (B, N, 2)
        cov = np.einsum("bn,bni,bnj->bij", w, dp, dp)
        return p_mean, psi_mean, cov, np.einsum("bn,bn->b", w, wrap_angle(psis[None] - psi_mean[:, None]) ** 2)

    def _po_likelihoods(self, X: FloatArray, summary, ell: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Measurement likelihoods of PO particles ``X`` (K, N, 2) NED, marginalised over
        Gaussian vehicle beliefs ``summary`` (:meth:`_vehicle_summaries`, B = 1 for all POs or
        B = K, one per PO): ``N(ell_m; L, R^T P R + s^2 I + var_psi J J^T)`` with ``L`` the
        particle in the mean vehicle frame and ``J = d ell / d psi = [ell_across, -ell_along]``
        (heading linearised at the measurement). Returns (K, N, M) likelihoods (1/m^2) and (K, N)
        in-tile probabilities (:meth:`_in_tile_probability`)."""
        p_mean, psi_mean, P_s, var_psi = summary
        c, s = np.cos(psi_mean), np.sin(psi_mean)  # (B,)
        R = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)  # (B, 2, 2) vehicle -> NED
        P_loc = R.transpose(0, 2, 1) @ P_s @ R  # (B, 2, 2) vehicle frame
        J = np.stack([ell[:, 1], -ell[:, 0]], axis=1)  # (M, 2)
        S = ((P_loc + self.cfg.sigma_meas_m ** 2 * np.eye(2))[:, None]
             + var_psi[:, None, None, None] * (J[:, :, None] * J[:, None, :])[None])  # (B, M, 2, 2)
        det = (S[..., 0, 0] * S[..., 1, 1] - S[..., 0, 1] ** 2)[:, None, :]  # (B, 1, M)
        L = rotate_to_local(X - p_mean[:, None, :], psi_mean[:, None])  # (K, N, 2)
        e0 = ell[None, None, :, 0] - L[..., 0, None]
        e1 = ell[None, None, :, 1] - L[..., 1, None]  # (K, N, M)
        q2 = (S[:, None, :, 1, 1] * e0 * e0 - 2.0 * S[:, None, :, 0, 1] * e0 * e1 + S[:, None, :, 0, 0] * e1 * e1) / det
        sd_along = np.sqrt(P_loc[:, None, 0, 0] + var_psi[:, None] * L[..., 1] ** 2) + 1e-9
        sd_across = np.sqrt(P_loc[:, None, 1, 1] + var_psi[:, None] * L[..., 0] ** 2) + 1e-9
        return np.exp(-0.5 * q2) / (2.0 * np.pi * np.sqrt(det)), self._in_tile_probability(L, sd_along, sd_across)

    def _in_tile_probability(self, L: FloatArray, sd_along: FloatArray, sd_across: FloatArray) -> FloatArray:
        """Probability that a point at vehicle-frame ``L`` (..., 2), blurred by independent
        Gaussian errors (along, across; m), lies in the tile pair: the detection probability
        ``E_s[P_d]`` over the vehicle belief (a hard edge at the mean vehicle state turns every
        object near a tile boundary into a miss, then into a new PO)."""
        cfg = self.cfg
        a0, a1 = L[..., 0], L[..., 1]
        p_along = ndtr(-a0 / sd_along) - ndtr((-cfg.tile_length_m - a0) / sd_along)
        near, far = cfg.tile_near_m, cfg.tile_near_m + cfg.tile_width_m
        p_across = (ndtr((far - a1) / sd_across) - ndtr((near - a1) / sd_across)
                    + ndtr((-near - a1) / sd_across) - ndtr((-far - a1) / sd_across))
        return p_along * p_across

    @staticmethod
    def _summarise_pos(X: FloatArray) -> FloatArray:
        """(K, 3) position mean (north, east) and total variance of PO particles X (K, N, 2)."""
        mu = X.mean(axis=1)
        return np.concatenate([mu, ((X - mu[:, None]) ** 2).sum(-1).mean(1)[:, None]], axis=1)

    def _relevant(self, veh: FloatArray) -> NDArray[np.intp]:
        """POs whose belief may reach the tile (mean within the tile grown by 3 sigma + 10 m)."""
        if len(self.r) == 0:
            return np.zeros(0, dtype=np.intp)
        cfg = self.cfg
        if len(self._po_stats) != len(self.r):  # set from outside: summarise every PO again
            self._po_stats = self._summarise_pos(self.X)
        mu = self._po_stats[:, :2]  # (K, 2), position means
        sd = np.sqrt(self._po_stats[:, 2] + veh[:, :2].var(axis=0).sum())
        vm = veh.mean(axis=0)
        L = rotate_to_local(mu - vm[:2], np.full(len(mu), np.arctan2(vm[3], vm[2])))
        grow = 3.0 * sd + 10.0
        a = np.abs(L[:, 1])
        ok = ((L[:, 0] >= -cfg.tile_length_m - grow) & (L[:, 0] <= grow) & (a >= cfg.tile_near_m - grow)
              & (a <= cfg.tile_near_m + cfg.tile_width_m + grow))
        return np.flatnonzero(ok)

    def _po_to_vehicle_messages(self, rel, ell, f_pi, nu, ratio) -> FloatArray:
        """Log-messages (Kr, N) from the legacy POs ``rel`` to the vehicle particles (paper 003,
        IV-D, ``zeta_{q_k -> s}``; Gaussian summary of each PO belief); the vehicle particles are
        equally weighted on entry."""
        cfg = self.cfg
        sig2 = cfg.sigma_meas_m ** 2
        pos, psi = self.S[:, :2], heading_rad(self.S)
        W = self.W[rel]
        q = W.sum(-1)  # (Kr, N) position weights
        mu = np.einsum("kn,knd->kd", q, self.X[rel])
        dx = self.X[rel] - mu[:, None, :]
        P = np.einsum("kn,kni,knj->kij", q, dx, dx)  # (Kr, 2, 2)
        p00, p01, p11 = P[:, 0, 0, None], P[:, 0, 1, None], P[:, 1, 1, None]
        L = rotate_to_local(mu[:, None, :] - pos[None], psi[None])  # (Kr, N, 2)
        c, s = np.cos(psi), np.sin(psi)
        # R^T P R per vehicle particle
        a11 = c * c * p00 + 2 * c * s * p01 + s * s * p11 + sig2
        a22 = s * s * p00 - 2 * c * s * p01 + c * c * p11 + sig2
        a12 = (c * c - s * s) * p01 + c * s * (p11 - p00)
        det = a11 * a22 - a12 * a12  # (Kr, N)
        inside = self._in_tile_probability(L, np.sqrt(a11 - sig2) + 1e-9, np.sqrt(a22 - sig2) + 1e-9)
        e0 = ell[None, None, :, 0] - L[..., 0, None]
        e1 = ell[None, None, :, 1] - L[..., 1, None]  # (Kr, N, M)
        q2 = (a22[..., None] * e0 * e0 - 2 * a12[..., None] * e0 * e1 + a11[..., None] * e1 * e1) / det[..., None]
        lik = np.exp(-0.5 * q2) / (2 * np.pi * np.sqrt(det))[..., None]
        det_term = np.einsum("knm,km->kn", lik, nu * (W.sum(1) @ f_pi.T))  # sum_m nu lik f(pi_m)
        rk = self.r[rel][:, None]
        gamma = (1.0 - rk) + rk * ((1.0 - cfg.pd * inside) + cfg.pd * ratio * det_term)
        return np.log(np.maximum(gamma, 1e-300))

    def _update_legacy(self, rel, veh, ell, f_pi, nu, ratio, ext_logw, terms=None) -> None:
        """PO beliefs from the association messages (paper 003, IV-D/E, ``zeta_{q_k -> y_k}``):
        the vehicle belief each PO sees is the extrinsic one (every message but its own,
        ``ext_logw`` (Kr, N) log-weights over ``veh``), as a Gaussian summary. In the point
        modes that is the equally weighted one for every PO, whose :meth:`_po_likelihoods` the
        association already computed (``terms``, reused when given)."""
        cfg = self.cfg
        n = cfg.n_particles
        if cfg.mode == "spa":  # one extrinsic vehicle belief per PO
            lw = np.exp(ext_logw - ext_logw.max(axis=1, keepdims=True))
            terms = self._po_likelihoods(self.X[rel], self._vehicle_summaries(veh, lw / lw.sum(axis=1, keepdims=True)),
                                         ell)
        elif terms is None:
            terms = self._po_likelihoods(self.X[rel], self._uniform_vehicle_summary(veh), ell)
        lik, inside = terms  # (Kr, N, M), (Kr, N)
        acc = np.einsum("knm,km,mc->knc", lik, nu, f_pi)  # (Kr, N, C)
        factor = (1.0 - cfg.pd * inside)[..., None] + cfg.pd * ratio * acc
        w = self.W[rel] * factor
        q_all = np.einsum("knc->kn", w)  # (Kr, N) position weights
        z = q_all.sum(axis=1)
        rk = self.r[rel]
        self.r[rel] = rk * z / (rk * z + 1.0 - rk)
        for j, k in enumerate(rel):
            if z[j] <= 0.0:
                continue
            wk = w[j] / z[j]
            q = q_all[j] / z[j]
            if 1.0 / np.dot(q, q) < 0.5 * n:
                idx = systematic_resample(q, self.rng)
                X = self.X[k][idx]
                self.X[k] = X + self._roughening(X)
                self.W[k] = wk[idx] / q[idx][:, None] / n
            else:
                self.W[k] = wk
        if len(self._po_stats) == len(self.r):
            self._po_stats[rel] = self._summarise_pos(self.X[rel])

    def _add_new(self, veh, ell, f_pi, xi, phi_sum) -> None:
        cfg = self.cfg
        n = cfg.n_particles
        m_n = len(ell)
        if m_n == 0:
            return
        r_new = (xi - 1.0) / (xi + phi_sum)
        j = self.rng.integers(0, n, (m_n, n))
        noisy = ell[:, None, :] + cfg.sigma_meas_m * self.rng.standard_normal((m_n, n, 2))
        X = veh[j, :2] + rotate_to_ned(noisy, heading_rad(veh)[j])
        pc = f_pi / f_pi.sum(axis=1, keepdims=True)
        W = np.repeat(pc[:, None, :], n, axis=1) / n
        if len(self._po_stats) == len(self.r):
            self._po_stats = np.concatenate([self._po_stats, self._summarise_pos(X)])
        self.r = np.concatenate([self.r, r_new])
        self.X = np.concatenate([self.X, X])
        self.W = np.concatenate([self.W, W])

    # -- outputs ----------------------------------------------------------------------------
    def estimate(self, threshold: float | None = None) -> MapEstimate:
        """Confirmed objects: existence above ``threshold`` (default ``E_th``)."""
        th = self.cfg.confirm_threshold if threshold is None else threshold
        sel = np.flatnonzero(self.r > th)
        W = self.W[sel]
        w_cls = W.sum(axis=1)  # (J, C)
        pos = np.einsum("kic,kid->kd", W, self.X[sel]) / np.maximum(w_cls.sum(1, keepdims=True), 1e-300)
        cls = np.argmax(w_cls, axis=1) if len(sel) else np.zeros(0, dtype=np.intp)
        return MapEstimate(pos.reshape(-1, 2), cls.astype(np.intp), self.r[sel].copy())
