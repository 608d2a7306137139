"""Probabilistic multiple hypothesis anchoring (PMHA) world model (paper 000 section V).

Every hypothesis is one admissible world: a set of anchors. Each scan, every measurement
is a new object, an existing anchor of the parent hypothesis, or clutter, at most one
measurement per anchor. The child probability (eqs. 10-16, Reid's MHT with Poisson new and
clutter counts) is, up to a per-scan constant,

    p(parent) * prod_{j -> new} p_new u_new c0 * prod_{j -> clutter} p_clutter u_clutter c0
              * prod_{j -> a} p_existing P_D(a) N(z_j; x_a, P_a + R_j) c(a, j)
              * prod_{a not detected} (1 - P_D(a)),

with u the uniform densities over the surveyed volume, P_D(a) = p_detect * max(p(visible | x_a), visibility_floor),
c(a, j) = class_pmf(a) . q(z_j) the class likelihood and c0 = 1/2 its value under the
uniform class prior. The product factorises over (measurement, origin) pairs, so the
children of a parent in decreasing probability are the ranked assignments of a cost
matrix: rows are split into groups linked by a shared gated anchor, multi-row groups are
ranked with Murty's algorithm (``linear_sum_assignment`` inside) and the groups' lists are
combined best-first (:func:`autonomy.estimation.assignment.ranked_associations`, exact).
Children of all parents are drawn best-first from one heap until ``max_hypotheses``
distinct worlds are found or the next one falls below ``prune_ratio`` times the best;
children with identical anchor sets are merged (probabilities added), which also happens
when unconfirmed anchors age out (``drop_tentative_after_s``). The most probable
hypothesis is the world model.

Two measures keep near-identical hypotheses from crowding out distinct worlds. Detections
of one scan consistent with a single point (two boxes on one object) enter as one cluster
measurement (``scan_cluster_mahalanobis2``, :mod:`autonomy.estimation.clustering`), so one
object never spawns a phantom twin. When the budget is full, anchor versions of one symbol
with the same detection count within ``merge_mahalanobis2`` of each other are taken as one
(hypotheses differing only in them merge, probabilities added), each distinct set of
objects keeps at most ``max_per_world`` hypotheses, and children are drawn until the budget
again holds ``max_hypotheses`` distinct worlds: the budget keeps the best of each world
rather than permutations of one, and a birth is not starved. Below the budget the tree is
exact.

Should the best world still hold two anchors of one object (a second anchor born when one
look fell outside the first's gate, each then absorbing some of the object's detections),
the reported world model joins them: the track-to-track test and fusion of
:mod:`autonomy.estimation.track_fusion` ([BarShalomCampo1986]), their shared errors as the
cross-covariance (``duplicate_mahalanobis2``, ``duplicate_max_separation_m``). The hypothesis
tree itself is unchanged.

The model is assembled from the estimation roles of :mod:`autonomy.estimation`: a
constant-position transition with a Kalman predictor (and its fixed-Gaussian fallback), an
identity position-fix measurement model with a Kalman updater and a single-measurement
initiator, a same-scan clusterer, a Mahalanobis gater, a k-best (Murty) data associator and
an update-time deleter for tentative anchors; PMHA adds the hypothesis tree, detection
probabilities and class pmf. The Kalman and class posteriors of all gated (anchor,
measurement) pairs of a scan are computed in one batch, bit for bit the per-pair ones
(:meth:`autonomy.estimation.updater.KalmanUpdater.update_batch`); a child takes its pair's.
"""

from __future__ import annotations

import dataclasses
import heapq
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.estimation.assignment import LazyRanked
from autonomy.estimation.association import KBestAssociator
from autonomy.estimation.clustering import cluster_consistent, fuse_cluster
from autonomy.estimation.deleter import UpdateTimeDeleter
from autonomy.estimation.gater import MahalanobisGater, innovation_log_likelihoods
from autonomy.estimation.initiator import SingleMeasurementInitiator
from autonomy.estimation.measurement import PositionFix
from autonomy.estimation.predictor import KalmanPredictor
from autonomy.estimation.track_fusion import cross_covariance, fuse_tracks, track_distance2
from autonomy.estimation.transition import ConstantPosition
from autonomy.estimation.updater import ConsiderKalmanUpdater
from autonomy.localization.geolocate import SHARED_ERRORS, LocalizedDetection
from autonomy.world_model.anchor import (
    CLASS_NAMES,
    Anchor,
    class_likelihood,
    class_update,
    class_update_batch,
    measurement_cov,
    measurement_shared,
)
from autonomy.world_model.config import WorldModelConfig

FloatArray = NDArray[np.float64]
Visibility = Callable[[FloatArray], ArrayLike]
_PD_MAX = 1.0 - 1e-12
_NEW, _CLUTTER = -1, -2  # private origin labels of a measurement


@dataclass(frozen=True, slots=True)
class Hypothesis:
    """One world: its posterior probability and its anchors."""

    probability: float
    anchors: tuple[Anchor, ...]


@dataclass(frozen=True, slots=True)
class WorldObject:
    """An object of the world model (paper 000 Table VI)."""

    id: int
    class_pmf: FloatArray  # (2,) over CLASS_NAMES
    pos_ned: FloatArray  # (3,)
    cov_ned: FloatArray  # (3, 3)
    n_detections: int
    existence_probability: float  # total probability of the hypotheses holding this object (any symbol of it)
    #: symbols of duplicate anchors joined into this object (empty: none); see PMHA.world_model
    merged_ids: tuple[int, ...] = ()

    @property
    def class_name(self) -> str:
        return CLASS_NAMES[int(np.argmax(self.class_pmf))]

    def to_dict(self) -> dict:
        return {
            "id": self.id,
            "class_name": self.class_name,
            "class_pmf": dict(zip(CLASS_NAMES, map(float, self.class_pmf))),
            "pos_ned": [float(v) for v in self.pos_ned],
            "cov_ned": [[float(v) for v in row] for row in self.cov_ned],
            "n_detections": self.n_detections,
            "existence_probability": self.existence_probability,
            "merged_ids": list(self.merged_ids),
        }


class PMHA:
    """PMHA world model.

    Args:
        cfg: world-model config.
        region_ned: optional ((3,) min, (3,) max) corners of the surveyed volume; when given,
            the new and clutter densities are 1 / its volume, else the configured densities.
            The new-object density is zero outside it: a measurement outside the surveyed
            volume can update an existing anchor or be clutter, never start an object.
    """

    def __init__(
        self, cfg: WorldModelConfig, region_ned: tuple[ArrayLike, ArrayLike] | None = None
    ) -> None:
        self.cfg = cfg
        self._region: tuple[np.ndarray, np.ndarray] | None = None
        if region_ned is None:
            log_u_new = math.log(cfg.new_density_per_m3)
            log_u_clutter = math.log(cfg.clutter_density_per_m3)
        else:
            lo, hi = (np.asarray(v, dtype=float).reshape(3) for v in region_ned)
            self._region = (lo, hi)
            volume = float(np.prod(hi - lo))
            if not volume > 0.0:
                raise ValueError(f"PMHA region_ned must have positive volume, got {lo} .. {hi}")
            log_u_new = log_u_clutter = -math.log(volume)
        log_c0 = math.log(0.5) if cfg.use_class_likelihood else 0.0
        self._log_new = math.log(cfg.p_new) + log_u_new + log_c0
        self._log_clutter = math.log(cfg.p_clutter) + log_u_clutter + log_c0
        self._log_existing = math.log(cfg.p_existing)
        # estimation roles
        self.transition = ConstantPosition(cfg.process_noise_m2_per_s, ndim=3)
        self.predictor = KalmanPredictor(self.transition, cfg.kf_timeout_s, cfg.fallback_cov_m2 * np.eye(3))
        self.measurement_model = PositionFix(3, (0, 1, 2))  # NED position; covariance per detection
        self.updater = ConsiderKalmanUpdater(self.measurement_model)
        # shared errors enter only with the localisation's own covariances
        self._consider = cfg.consider_shared_errors and cfg.measurement_cov_m2 is None
        self.gater = MahalanobisGater(cfg.gate_mahalanobis2)
        self.initiator = SingleMeasurementInitiator(self.measurement_model)
        self.deleter = (
            None if cfg.drop_tentative_after_s is None
            else UpdateTimeDeleter(cfg.drop_tentative_after_s, min_updates=cfg.min_detections)
        )
        self._log_w = np.zeros(1)
        self._hyps: list[frozenset[int]] = [frozenset()]  # anchor versions of each world
        self._anchors: dict[int, Anchor] = {}  # version -> anchor, for all live versions
        self._next_uid = 0
        self._next_version = 0
        self.t_s = float("-inf")
        self.n_scans = 0

    # ------------------------------------------------------------------ update
    def update(
        self,
        t_s: float,
        measurements: Sequence[LocalizedDetection],
        visible: Visibility | None = None,
    ) -> None:
        """Process one scan taken at ``t_s``.

        ``visible(points_ned (N, 3)) -> (N,)`` gives, for anchor positions, whether (bool) or
        how likely (float in [0, 1]) they lay inside the sonar field of view at ``t_s``
        (e.g. :func:`autonomy.localization.fls_visibility`); None means every anchor was.

        The steps ([P000] section V; named as Stone Soup's tracker composes its roles
        [StoneSoup]): the scan's anchors and their detection probabilities
        (:meth:`_scan_anchors`), the gated associations and their posteriors (:meth:`_gate`),
        the children hypotheses drawn best first (:meth:`_expand`), and the normalised,
        pruned hypothesis set kept (:meth:`_keep`).

        Raises:
            ValueError: ``t_s`` before the last scan; ``visible`` of the wrong shape.
        """
        t_s = float(t_s)
        if t_s < self.t_s:
            raise ValueError(f"PMHA.update: time went backwards ({t_s} < {self.t_s})")
        scan = self._scan_anchors(t_s, self.cluster_scan(measurements), visible)
        self._gate(scan)
        expansion = _Expansion(self, scan)
        expansion.run()
        self._keep(scan, expansion)

    def _scan_anchors(self, t_s: float, measurements: list[LocalizedDetection], visible: Visibility | None) -> _Scan:
        """The scan's measurements and new ids, the anchors of the present hypotheses and
        their detection probability and miss factor."""
        cfg = self.cfg
        m = len(measurements)
        uids = list(range(self._next_uid, self._next_uid + m))
        self._next_uid += m
        versions = sorted(frozenset().union(*self._hyps))
        anchors = [self._anchors[v] for v in versions]
        n_u = len(anchors)
        if n_u:
            X = np.stack([a.pos_ned for a in anchors])
            vis = np.ones(n_u) if visible is None else np.asarray(visible(X), dtype=float)
            if vis.shape != (n_u,):
                raise ValueError(f"visible() must return shape ({n_u},), got {vis.shape}")
            p_d = np.clip(cfg.p_detect * np.maximum(vis, cfg.visibility_floor), 0.0, _PD_MAX)
            log_miss = np.log1p(-p_d)
        else:
            X = np.zeros((0, 3))
            p_d = log_miss = np.zeros(0)
        return _Scan(t_s=t_s, measurements=measurements, uids=uids, versions=versions, anchors=anchors, X=X,
                     p_d=p_d, log_miss=log_miss, log_miss_of=dict(zip(versions, log_miss.tolist())),
                     anchor_of=dict(zip(versions, anchors)))

    def _gate(self, scan: _Scan) -> None:
        """Per measurement, the gated anchors with their cost (-log weight relative to a miss),
        the posteriors of the gated pairs, the private options (new object, clutter), the
        associator, and the tentative anchors that age out in this scan."""
        cfg, measurements, anchors = self.cfg, scan.measurements, scan.anchors
        m, n_u = len(measurements), len(anchors)
        if m:
            scan.Z = np.stack([np.asarray(z.pos_ned, dtype=float) for z in measurements])
            scan.R = np.stack([measurement_cov(z, cfg) for z in measurements])
            scan.Q = np.stack([class_likelihood(z.class_score, cfg) for z in measurements])  # (m, 2)
            scan.Ls = np.stack([measurement_shared(z) for z in measurements]) if self._consider else None
        if m and n_u:
            dt = np.maximum(scan.t_s - np.array([a.t_last_s for a in anchors]), 0.0)
            scan.P_pred = self.predictor.predict_covar(np.stack([a.cov_ned for a in anchors]), dt)
            if self._consider:
                scan.M_pred = np.stack([self._sens(a) for a in anchors])
                # after the timeout the position is a fresh fixed Gaussian, sharing nothing
                scan.M_pred[dt > cfg.kf_timeout_s] = 0.0
            pmf = np.stack([a.class_pmf for a in anchors])  # (n_u, 2)
            assoc = self._association_logw(scan.X, scan.P_pred, scan.p_d, scan.log_miss, pmf, scan.Z, scan.R, scan.Q,
                                           scan.M_pred, scan.Ls)
            inside = np.isfinite(assoc)
            gated = [[(scan.versions[u], -float(assoc[u, j])) for u in np.flatnonzero(inside[:, j])]
                     for j in range(m)]
            scan.row_of = dict(zip(scan.versions, range(n_u)))
            scan.posterior = self._posteriors(scan.versions, scan.X, scan.P_pred, pmf, scan.Z, scan.R, scan.Q, inside,
                                              scan.M_pred, scan.Ls)
        else:
            gated = [[] for _ in range(m)]
        private_in = [(_NEW, -self._log_new), (_CLUTTER, -self._log_clutter)]
        private_out = [(_CLUTTER, -self._log_clutter)]
        privates = [private_in if self._in_region(z.pos_ned) else private_out for z in measurements]
        scan.associator = KBestAssociator(gated, privates)
        if self.deleter is not None:  # tentative anchors that age out (merged into the "clutter" worlds)
            scan.stale = frozenset(a.version for a in anchors
                                   if self.deleter.deletes(scan.t_s, a.t_last_s, a.n_detections))

    def _keep(self, scan: _Scan, expansion: _Expansion) -> None:
        """The children as the new hypotheses: the best within the budget, normalised, best
        first; the anchors they use kept, the others dropped."""
        cfg = self.cfg
        child_hyps = list(expansion.children)
        lw = np.asarray(expansion.child_logw)
        if len(child_hyps) > cfg.max_hypotheses:  # worlds found beyond the budget: keep the best
            keep = np.sort(np.argsort(-lw, kind="stable")[: cfg.max_hypotheses])
            child_hyps = [child_hyps[i] for i in keep]
            lw = lw[keep]
        lw -= lw.max()
        lw -= math.log(np.exp(lw).sum())
        order = np.argsort(-lw, kind="stable")
        self._hyps = [child_hyps[i] for i in order]
        self._log_w = lw[order]
        live = frozenset().union(*self._hyps)
        for a in (*scan.anchors, *expansion.update_cache.values(), *expansion.birth_cache.values()):
            if a.version in live:
                self._anchors[a.version] = a
        self._anchors = {v: self._anchors[v] for v in live}
        self.t_s = scan.t_s
        self.n_scans += 1

    def cluster_scan(self, measurements: Sequence[LocalizedDetection]) -> list[LocalizedDetection]:
        """The scan with detections consistent with one point fused into one measurement
        (:mod:`autonomy.estimation.clustering`; visited by decreasing ATR score). A fused
        measurement's class score is its members' mean. Order: by each cluster's first
        detection."""
        gate = self.cfg.scan_cluster_mahalanobis2
        measurements = list(measurements)
        if gate is None or len(measurements) < 2:
            return measurements
        Z = np.stack([np.asarray(z.pos_ned, dtype=float) for z in measurements])
        R = np.stack([measurement_cov(z, self.cfg) for z in measurements])
        order = sorted(range(len(measurements)), key=lambda j: (-measurements[j].class_score, j))
        clusters = cluster_consistent(Z, R, gate, order)
        if len(clusters) == len(measurements):
            return measurements
        out = []
        for members in sorted(clusters, key=min):
            first = measurements[min(members)]
            if len(members) == 1:
                out.append(first)
                continue
            pos, cov = fuse_cluster(Z[members], R[members])
            score = float(np.mean([measurements[j].class_score for j in members]))
            # the members' errors are taken as fully correlated (fuse_cluster): so are their shared parts
            shared = (np.mean([measurement_shared(measurements[j]) for j in members], axis=0)
                      if self._consider else first.shared_ned)
            out.append(dataclasses.replace(first, pos_ned=pos, cov_ned=cov, class_score=score, shared_ned=shared))
        return out

    def _register(
        self, a: Anchor, canon: dict[int, int], reps: dict[int, list[Anchor]], id_of: dict[int, int]
    ) -> None:
        """Map version ``a`` to the first registered version of its symbol with the same
        detection count whose position is within the merge gate (else to itself)."""
        gate = self.cfg.merge_mahalanobis2
        id_of[a.version] = a.id
        same = reps.setdefault(a.id, [])
        for r in same:
            if r.n_detections == a.n_detections:
                d = a.pos_ned - r.pos_ned
                if float(d @ np.linalg.solve(a.cov_ned + r.cov_ned, d)) <= gate:
                    canon[a.version] = r.version
                    return
        same.append(a)
        canon[a.version] = a.version


    @staticmethod
    def _merged(
        children: dict[frozenset[int], int], child_logw: list[float], canon: dict[int, int]
    ) -> tuple[dict[frozenset[int], int], list[float]]:
        """Children re-keyed by representative versions; equal worlds' weights added."""
        moved = frozenset(v for v, r in canon.items() if v != r)
        if not moved:
            return children, child_logw
        merged: dict[frozenset[int], int] = {}
        logw: list[float] = []
        for child, i in children.items():
            key = child if child.isdisjoint(moved) else frozenset(map(canon.__getitem__, child))
            k = merged.get(key)
            if k is None:
                merged[key] = len(logw)
                logw.append(child_logw[i])
            else:
                logw[k] = float(np.logaddexp(logw[k], child_logw[i]))
        return merged, logw

    def _in_region(self, pos_ned: np.ndarray) -> bool:
        if self._region is None:
            return True
        lo, hi = self._region
        p = np.asarray(pos_ned, dtype=float)
        return bool(np.all(p >= lo) and np.all(p <= hi))

    def _association_logw(
        self,
        X: FloatArray,
        P_pred: FloatArray,
        p_d: FloatArray,
        log_miss: FloatArray,
        pmf: FloatArray,
        Z: FloatArray,
        R: FloatArray,
        Q: FloatArray,
        M: FloatArray | None = None,
        L: FloatArray | None = None,
    ) -> FloatArray:
        """Log weight (n_u, m) of each anchor-measurement pair relative to the anchor's miss;
        -inf outside the gate. ``pmf`` (n_u, 2): the anchors' class pmfs; ``Q`` (m, 2): the
        measurements' class likelihoods; ``M`` (n_u, 3, q) and ``L`` (m, 3, q): the anchors'
        and measurements' shared-error sensitivities (None: nothing shared)."""
        cfg = self.cfg
        model = self.measurement_model
        shared = None
        if M is not None and L is not None:
            C = np.einsum("uaq,jbq->ujab", M[:, model.mapping], L)
            shared = C + C.swapaxes(-1, -2)
        maha2, loglik = innovation_log_likelihoods(model.function(X), model.project_covar(P_pred), Z, R, shared)
        with np.errstate(divide="ignore"):
            logw = self._log_existing + np.log(p_d)[:, None] + loglik - log_miss[:, None]
        if cfg.use_class_likelihood:
            logw = logw + np.log(pmf @ Q.T)
        logw[self.gater.rejects(maha2)] = -np.inf
        return logw

    def _posteriors(
        self, versions: list[int], X: FloatArray, P_pred: FloatArray, pmf: FloatArray, Z: FloatArray,
        R: FloatArray, Q: FloatArray, inside: NDArray[np.bool_], M: FloatArray | None = None,
        L: FloatArray | None = None,
    ) -> dict[tuple[int, int], tuple]:
        """Kalman and class posteriors of every gated (anchor u, measurement j) pair in one
        batch, keyed ``(version of u, j)``: ``(pos_ned (3,), cov_ned (3, 3), class_pmf (2,),
        consider_ned (3, q) or None)``, each bit for bit what :meth:`_updated` computes for the
        pair alone (:meth:`ConsiderKalmanUpdater.update_consider_batch` with shared errors,
        else :meth:`KalmanUpdater.update_batch`; :func:`class_update_batch`). Empty when an
        innovation covariance is singular: the pairs are then updated one by one when drawn,
        so the error is raised only for a pair a child uses, as before."""
        us, js = np.nonzero(inside)
        if us.size == 0:
            return {}
        try:
            if M is None:
                x, P = self.updater.update_batch(X[us], P_pred[us], Z[js], R[js])
                Mn = [None] * len(us)
            else:
                x, P, Mn = self.updater.update_consider_batch(X[us], P_pred[us], M[us], Z[js], R[js], L[js])
        except np.linalg.LinAlgError:
            return {}
        post = class_update_batch(pmf[us], Q[js])
        return {(versions[u], j): (x[i], P[i], post[i], Mn[i])
                for i, (u, j) in enumerate(zip(us.tolist(), js.tolist()))}

    def _updated(
        self, anchor: Anchor, posterior: tuple[FloatArray, FloatArray, FloatArray] | None, P_pred: FloatArray,
        z_pos: FloatArray, R: FloatArray, q: FloatArray, uid: int, t_s: float,
        M_pred: FloatArray | None = None, L: FloatArray | None = None,
    ) -> Anchor:
        """New version of ``anchor`` after measurement ``z_pos`` (3,) with noise ``R`` (3, 3)
        and class likelihood ``q`` (2,): Kalman (consider, with the anchor's ``M_pred`` and
        the measurement's ``L`` shared-error sensitivities) and class updates, or their
        ``posterior`` precomputed by :meth:`_posteriors`."""
        M = None
        if posterior is None:
            if M_pred is None:
                x, P = self.updater.update(anchor.pos_ned, P_pred, z_pos, R)
            else:
                x, P, M = self.updater.update_consider(anchor.pos_ned, P_pred, M_pred, z_pos, R, L)
            pmf = class_update(anchor.class_pmf, q)
        else:
            x, P, pmf = (v.copy() for v in posterior[:3])
            M = None if posterior[3] is None else posterior[3].copy()
        return Anchor(
            id=anchor.id,
            version=self._version(),
            pos_ned=x,
            cov_ned=P,
            t_last_s=float(t_s),
            n_detections=anchor.n_detections + 1,
            class_pmf=pmf,
            measurement_ids=anchor.measurement_ids + (uid,),
            consider_ned=M,
        )

    @staticmethod
    def _sens(a: Anchor) -> FloatArray:
        return np.zeros((3, len(SHARED_ERRORS))) if a.consider_ned is None else a.consider_ned

    def _born(self, z: LocalizedDetection, z_pos: FloatArray, R: FloatArray, uid: int,
              L: FloatArray | None = None) -> Anchor:
        """Anchor initialised from its first measurement (the uid becomes its symbol); its
        position error shares the measurement's shared part ``L`` (3, q)."""
        x, P = self.initiator.initiate(z_pos, R)
        return Anchor(
            id=uid,
            version=self._version(),
            pos_ned=x,
            cov_ned=P,
            t_last_s=float(z.t_s),
            n_detections=1,
            class_pmf=class_likelihood(z.class_score, self.cfg),
            measurement_ids=(uid,),
            consider_ned=None if L is None else L.copy(),
        )

    def _version(self) -> int:
        self._next_version += 1
        return self._next_version

    # ------------------------------------------------------------------ outputs
    @property
    def hypotheses(self) -> list[Hypothesis]:
        """All hypotheses, most probable first."""
        p = np.exp(self._log_w)
        return [Hypothesis(float(pi), self._world(hyp)) for pi, hyp in zip(p, self._hyps)]

    def _world(self, hyp: frozenset[int]) -> tuple[Anchor, ...]:
        return tuple(sorted((self._anchors[v] for v in hyp), key=lambda a: a.id))

    def world_model(self, min_detections: int | None = None) -> list[WorldObject]:
        """Objects of the most probable hypothesis with enough supporting detections.

        Two of them that are one object by the track-to-track test
        (``duplicate_mahalanobis2`` within ``duplicate_max_separation_m``) are reported as one:
        the symbol with more detections, the two estimates fused (Bar-Shalom-Campo, their
        shared errors as the cross-covariance), the detections summed and the class pmfs
        multiplied (both are posteriors from the uniform prior).

        An object's existence is the probability of the hypotheses that hold it, under its own
        symbol or under another one the same test says is the same object: a world where one
        detection of it was a false alarm starts the object's anchor a detection later, under
        a new symbol, at the same place. Counting only the reported symbol would leave an
        object seen hundreds of times short of certain (0.94-0.98 with the navigation
        estimate). With the test off (``duplicate_mahalanobis2: None``), the symbols' own.
        """
        n_min = self.cfg.min_detections if min_detections is None else min_detections
        shown = [a for a in self._world(self._hyps[0]) if a.n_detections >= n_min]
        groups = self._duplicate_groups(shown)
        of_symbol, of_version = self._same_objects(groups)
        weights = np.exp(self._log_w)
        exist: dict[int, float] = {}
        for p, hyp in zip(weights.tolist(), self._hyps):
            held = {of_symbol.get(self._anchors[v].id, of_version.get(v)) for v in hyp}
            for i in held:
                if i is not None:
                    exist[i] = exist.get(i, 0.0) + p
        out = []
        for a in shown:
            members = groups.get(a.id)
            if members is None:
                continue
            p_exist = min(exist.get(a.id, 0.0), 1.0)
            if len(members) == 1:
                out.append(WorldObject(id=a.id, class_pmf=a.class_pmf.copy(), pos_ned=a.pos_ned.copy(),
                                       cov_ned=a.cov_ned.copy(), n_detections=a.n_detections,
                                       existence_probability=p_exist))
            else:
                out.append(self._fused_object(members, p_exist))
        return out

    def _same_objects(self, groups: dict[int, list[Anchor]]) -> tuple[dict[int, int], dict[int, int]]:
        """Which reported object each anchor of the hypotheses is: ({symbol: reported symbol}
        for the groups' members, {version: reported symbol} for the versions of every other
        symbol that pass the duplicate test with a group's kept anchor, nearest first). With
        the test off, each shown symbol is itself and nothing else is mapped."""
        of_symbol = {a.id: kept for kept, members in groups.items() for a in members}
        of_version: dict[int, int] = {}
        others = [b for b in self._anchors.values() if b.id not in of_symbol]
        if self.cfg.duplicate_mahalanobis2 is None or not groups or not others:
            return of_symbol, of_version
        kept = [members[0] for members in groups.values()]
        D = np.linalg.norm(np.array([b.pos_ned for b in others])[:, None, :]
                           - np.array([k.pos_ned for k in kept])[None], axis=2)
        for i in np.flatnonzero((D <= self.cfg.duplicate_max_separation_m).any(axis=1)):
            b = others[int(i)]
            for j in np.argsort(D[i], kind="stable"):
                if self._is_same_object(kept[int(j)], b):
                    of_version[b.version] = kept[int(j)].id
                    break
        return of_symbol, of_version

    def _is_same_object(self, k: Anchor, a: Anchor) -> bool:
        """The duplicate test: centres within ``duplicate_max_separation_m`` and the
        track-to-track squared Mahalanobis distance (their shared errors cancelled) within
        ``duplicate_mahalanobis2`` (which must not be None)."""
        if np.linalg.norm(a.pos_ned - k.pos_ned) > self.cfg.duplicate_max_separation_m:
            return False
        P12 = cross_covariance(k.consider_ned, a.consider_ned, 3)
        return track_distance2(k.pos_ned, k.cov_ned, a.pos_ned, a.cov_ned, P12) <= self.cfg.duplicate_mahalanobis2

    def _duplicate_groups(self, anchors: list[Anchor]) -> dict[int, list[Anchor]]:
        """{symbol of the kept anchor: [it, the anchors that are the same object]} for every
        anchor of ``anchors``, greedily by detections (most first): an anchor joins the first
        kept one it passes the duplicate test with (no chaining)."""
        if self.cfg.duplicate_mahalanobis2 is None:
            return {a.id: [a] for a in anchors}
        groups: dict[int, list[Anchor]] = {}
        for a in sorted(anchors, key=lambda a: (-a.n_detections, a.id)):
            for members in groups.values():
                if self._is_same_object(members[0], a):
                    members.append(a)
                    break
            else:
                groups[a.id] = [a]
        return groups

    def _fused_object(self, members: list[Anchor], existence: float) -> WorldObject:
        """One :class:`WorldObject` of duplicate anchors (the first, with most detections, kept)."""
        k = members[0]
        x, P = k.pos_ned, k.cov_ned
        pmf = k.class_pmf.copy()
        for a in members[1:]:
            P12 = cross_covariance(k.consider_ned, a.consider_ned, 3)
            x, P = fuse_tracks(x, P, a.pos_ned, a.cov_ned, P12)
            pmf = class_update(pmf, a.class_pmf)
        return WorldObject(id=k.id, class_pmf=pmf, pos_ned=x, cov_ned=P,
                           n_detections=sum(a.n_detections for a in members), existence_probability=existence,
                           merged_ids=tuple(a.id for a in members[1:]))

    def to_json(self) -> dict:
        """JSON-ready world model (write with ``json.dump``)."""
        return {
            "t_s": self.t_s if np.isfinite(self.t_s) else None,
            "n_scans": self.n_scans,
            "n_hypotheses": len(self._hyps),
            "best_hypothesis_probability": float(np.exp(self._log_w[0])),
            "class_names": list(CLASS_NAMES),
            "objects": [o.to_dict() for o in self.world_model()],
        }


@dataclass
class _Scan:
    """One scan's working state in :meth:`PMHA.update` (anchors, measurements, gating)."""

    t_s: float
    measurements: list[LocalizedDetection]
    uids: list[int]
    versions: list[int]
    anchors: list[Anchor]
    X: FloatArray
    p_d: FloatArray
    log_miss: FloatArray
    log_miss_of: dict[int, float]
    anchor_of: dict[int, Anchor]
    Z: FloatArray | None = None
    R: FloatArray | None = None
    Q: FloatArray | None = None
    Ls: FloatArray | None = None
    P_pred: FloatArray | None = None
    M_pred: FloatArray | None = None
    row_of: dict[int, int] = dataclasses.field(default_factory=dict)
    posterior: dict[tuple[int, int], tuple] = dataclasses.field(default_factory=dict)
    associator: KBestAssociator | None = None
    stale: frozenset[int] = frozenset()


class _Expansion:
    """The children hypotheses of one scan, drawn best first from every parent's ranked
    associations ([P000] eqs. 14-16; murty-style lazy ranking, :class:`LazyRanked`).

    Once the budget is full, versions describing the same anchor state are merged (``canon``:
    version -> representative), each distinct set of objects (a world) keeps at most
    ``max_per_world`` hypotheses (further children add their probability to its best), and
    children are drawn until the budget is full again (or a budget's worth of draws brings no
    new world), so the budget holds the best of each distinct world instead of near-copies of one.
    """

    def __init__(self, pmha: PMHA, scan: _Scan) -> None:
        self.pmha, self.scan, self.cfg = pmha, scan, pmha.cfg
        self.update_cache: dict[tuple[int, int], Anchor] = {}
        self.birth_cache: dict[int, Anchor] = {}
        self.children: dict[frozenset[int], int] = {}
        self.child_logw: list[float] = []
        self.canon: dict[int, int] | None = None
        self.reps: dict[int, list[Anchor]] = {}
        self.id_of: dict[int, int] = {}  # registered version -> symbol
        self.world_of: dict[frozenset[int], list[int]] = {}  # object ids -> child indices, best first
        self.parent_keys: dict[int, tuple[frozenset[int], frozenset[int]]] = {}  # h -> (versions, ids)
        self.n_drawn = self.since_new_world = 0
        # parents offering the same options share one ranked list of associations
        self.heap: list[tuple[float, int, int]] = []
        self.parent_stream: list[LazyRanked] = []
        self.parent_base: list[float] = []
        for h, (log_w, hyp) in enumerate(zip(pmha._log_w.tolist(), pmha._hyps)):
            base = log_w + sum(map(scan.log_miss_of.__getitem__, hyp))
            stream = scan.associator.ranked(hyp)
            self.parent_stream.append(stream)
            self.parent_base.append(base)
            first = stream.get(0)
            if first is not None:
                self.heap.append((first[0] - base, h, 0))
        heapq.heapify(self.heap)

    def run(self) -> None:
        """Draw children until the heap is empty, the budget is full or the rest is pruned."""
        cfg, heap = self.cfg, self.heap
        log_floor = -np.inf
        while heap:
            if self.canon is None and len(self.children) >= cfg.max_hypotheses:
                if cfg.merge_mahalanobis2 is None:
                    break
                self._start_merging()
            if self.canon is not None:
                if (len(self.children) >= cfg.max_hypotheses or self.n_drawn >= cfg.max_expanded_children
                        or self.since_new_world >= cfg.max_hypotheses):
                    break
                self.n_drawn += 1
                self.since_new_world += 1
            neg, h, rank = heapq.heappop(heap)
            labels = self.parent_stream[h].get(rank)[1]
            logw = -neg
            if not self.children:
                log_floor = logw + math.log(cfg.prune_ratio)
            elif logw < log_floor:
                break
            child, objects = self._child(h, labels)
            self._add(child, objects, logw)
            nxt = self.parent_stream[h].get(rank + 1)
            if nxt is not None:
                heapq.heappush(heap, (nxt[0] - self.parent_base[h], h, rank + 1))

    def _start_merging(self) -> None:
        """The budget is full: register every anchor so far and re-key the children by their
        representative versions."""
        pmha, canon = self.pmha, {}
        self.canon = canon
        created = sorted((*self.update_cache.values(), *self.birth_cache.values()), key=lambda a: a.version)
        for a in (*self.scan.anchors, *created):
            pmha._register(a, canon, self.reps, self.id_of)
        self.children, self.child_logw = pmha._merged(self.children, self.child_logw, canon)
        for child, i in self.children.items():
            self.world_of.setdefault(frozenset(map(self.id_of.__getitem__, child)), []).append(i)

    def _anchor_after(self, j: int, lab: int) -> tuple[Anchor, bool]:
        """The anchor measurement ``j`` makes under label ``lab`` (an update of anchor version
        ``lab``, or a birth), made once per scan; and whether it is a birth."""
        pmha, scan, canon = self.pmha, self.scan, self.canon
        if lab >= 0:
            key = (lab, j)
            a = self.update_cache.get(key)
            if a is None:
                u = scan.row_of[lab]
                a = self.update_cache[key] = pmha._updated(
                    scan.anchor_of[lab], scan.posterior.get(key), scan.P_pred[u], scan.Z[j], scan.R[j], scan.Q[j],
                    scan.uids[j], scan.t_s, None if scan.M_pred is None else scan.M_pred[u],
                    None if scan.Ls is None else scan.Ls[j],
                )
                if canon is not None:
                    pmha._register(a, canon, self.reps, self.id_of)
            return a, False
        a = self.birth_cache.get(j)
        if a is None:
            a = self.birth_cache[j] = pmha._born(scan.measurements[j], scan.Z[j], scan.R[j], scan.uids[j],
                                                 None if scan.Ls is None else scan.Ls[j])
            if canon is not None:
                pmha._register(a, canon, self.reps, self.id_of)
        return a, True

    def _child(self, h: int, labels) -> tuple[frozenset[int], frozenset[int] | None]:
        """Parent ``h``'s child under ``labels`` (one per measurement: an anchor version,
        ``_NEW`` or ``_CLUTTER``): its versions and, once merging, its objects."""
        removed: list[int] = []
        added: list[int] = []
        born: list[int] = []
        for j, lab in enumerate(labels):
            if lab >= 0 or lab == _NEW:
                a, is_birth = self._anchor_after(j, lab)
                if is_birth:
                    born.append(a.id)
                else:
                    removed.append(lab)
                added.append(a.version)
        stale, canon, parent_hyp = self.scan.stale, self.canon, self.pmha._hyps[h]
        if canon is None:
            child = parent_hyp
            if removed or stale:
                child = child.difference(removed, stale)
            if added:
                child = child.union(added)
            return child, None
        # the parent's representative versions and objects, changed by this scan
        parent = self.parent_keys.get(h)
        if parent is None:
            rep = frozenset(map(canon.__getitem__, parent_hyp))
            parent = self.parent_keys[h] = (rep, frozenset(map(self.id_of.__getitem__, rep)))
        child, objects = parent
        gone = [canon[v] for v in stale if v in parent_hyp] if stale else []
        if removed or gone:
            child = child.difference(map(canon.__getitem__, removed), gone)
        if added:
            child = child.union(map(canon.__getitem__, added))
        if gone:
            objects = objects.difference(map(self.id_of.__getitem__, gone))
        if born:
            objects = objects.union(born)
        return child, objects

    def _add(self, child: frozenset[int], objects: frozenset[int] | None, logw: float) -> None:
        """Add ``child`` with weight ``logw`` (to an equal child's weight, or once merging to
        its world's best when the world is full)."""
        i = self.children.get(child)
        if i is None and self.canon is not None:
            world = self.world_of.setdefault(objects, [])
            if not world:
                self.since_new_world = 0
            if len(world) >= self.cfg.max_per_world:
                i = world[0]  # the world's best hypothesis absorbs the child
            else:
                world.append(len(self.child_logw))
        if i is None:
            self.children[child] = len(self.child_logw)
            self.child_logw.append(logw)
        else:
            self.child_logw[i] = float(np.logaddexp(self.child_logw[i], logw))
