"""Inspection planning: which world-model objects to look at again, from where, in what order.

The planner reads the onboard world model (:class:`autonomy.world_model.WorldObject`: mean,
covariance, class pmf, existence) and keeps its own record of the looks each object has had
(the bearing and ground range from which a frame detected it: an object's detection count
grows at that world-model update). It plans *inspection legs*: straight runs towards an
object along a chosen heading, from ``leg_start_range_m`` to ``leg_end_range_m`` of ground
range, so the forward-looking sonar sees it at short range from a new aspect.

Which objects ([P000] sections VI-VII: exploit the world model, never react to false alarms):

==========================  ==================================================================
test                        meaning
==========================  ==================================================================
confirmed                   existence >= ``confirm_existence`` and detections >=
                            ``confirm_detections``; an unconfirmed object is never visited
in the area                 inside the survey area grown by ``area_margin_m``; objects beyond
                            it (a basin wall's echoes) are not the survey's to inspect, nor
                            wait for
uncertain position          world-model 2-sigma horizontal semi-major > ``position_2sigma_m``,
                            its navigation part taken out (the vehicle's horizontal position
                            covariance now, :meth:`InspectionPlanner.set_navigation_covariance`:
                            every look shares it, so no leg can shrink it)
uncertain look geometry     the looks' predicted 2-sigma semi-major > ``look_2sigma_m``
uncertain class             class entropy > ``class_entropy_bits``
uncertain existence         existence < ``confident_existence``
==========================  ==================================================================

Look geometry (eq. 6 of [P000] with a flat seabed): a detection at ground range ``g`` from
altitude ``h`` (slant range ``r``) has an along-line-of-sight error of ``(r/g) sigma_r`` and
``(h/g) sigma_h`` and an across error of ``g sigma_a``, and where on the object the box
lands adds an aspect-dependent error (``aspect_sigma_m`` along, ``aspect_sigma_m / 2``
across) that repeated frames from one aspect do not average out. Each aspect bin
(``aspect_bin_deg``) contributes its best (shortest-range) look's information
``u u^T / s_along^2 + v v^T / s_across^2``; the look covariance is the inverse of their sum,
plus the reference-point bias: the box's reference point (its leading edge, moved by the
localisation's range offset) misses the object's centre by the same unknown distance
(``reference_bias_sigma_m``, one sigma) along every line of sight, so the fused estimate moves
by ``m = P sum_k I_k u_k`` per metre of it and the covariance gains
``reference_bias_sigma_m^2 m m^T``: looks from opposite sides cancel it, looks from one side
keep it whole. With it on, a leg is flown in its own direction (the opposite one is another
look).
A new look's heading is the one that most shrinks that covariance's largest eigenvalue
(E-optimal, [Pukelsheim1993]): it crosses the previous ellipse ([P000] eq. 6: the error grows with range and
with the elevation ambiguity; a new azimuth shrinks the ellipse across the previous one).

Order: an open tour from the vehicle through the legs, exact (Held-Karp dynamic programming,
[HeldKarp1962]) up to ``exact_tour_max`` legs, else nearest neighbour improved by 2-opt
([Croes1958]); each leg's direction
(its heading or the opposite one, same information) is the one whose start is nearer the
previous leg's end (unless the reference bias is modelled). Legs whose start or end leaves the
survey area grown by ``area_margin_m`` are not used (the next-best heading is).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class SurveyArea:
    """A rectangle in NED: corner ``origin_ne_m``, sides ``length_m`` along ``heading_rad`` and
    ``width_m`` across (to starboard of that heading, or port when ``across_sign`` is -1).

    Raises:
        ValueError: negative sides.
    """

    origin_ne_m: tuple[float, float]
    heading_rad: float
    length_m: float
    width_m: float
    across_sign: float = 1.0

    def __post_init__(self) -> None:
        if self.length_m < 0.0 or self.width_m < 0.0:
            raise ValueError(f"SurveyArea sides must be >= 0, got {self.length_m} x {self.width_m}")

    @property
    def along_ne(self) -> FloatArray:
        return np.array([math.cos(self.heading_rad), math.sin(self.heading_rad)])

    @property
    def across_ne(self) -> FloatArray:
        """Unit vector across the legs (starboard of the heading for ``across_sign`` 1)."""
        return self.across_sign * np.array([-math.sin(self.heading_rad), math.cos(self.heading_rad)])

    def local_m(self, pos_ne_m: ArrayLike) -> FloatArray:
        """(..., 2) (along, across) coordinates of NE points, m."""
        d = np.asarray(pos_ne_m, dtype=float)[..., :2] - np.asarray(self.origin_ne_m, dtype=float)
        return np.stack([d @ self.along_ne, d @ self.across_ne], axis=-1)

    def contains(self, pos_ne_m: ArrayLike, margin_m: float = 0.0) -> NDArray[np.bool_]:
        """Whether NE points ((..., 2) m) lie in the rectangle grown by ``margin_m``."""
        loc = self.local_m(pos_ne_m)
        return ((loc[..., 0] >= -margin_m) & (loc[..., 0] <= self.length_m + margin_m)
                & (loc[..., 1] >= -margin_m) & (loc[..., 1] <= self.width_m + margin_m))

    def corners_ne_m(self) -> FloatArray:
        """(4, 2) corners, in order round the rectangle."""
        o = np.asarray(self.origin_ne_m, dtype=float)
        f, a = self.along_ne * self.length_m, self.across_ne * self.width_m
        return np.array([o, o + f, o + f + a, o + a])


@dataclass(frozen=True, slots=True)
class PlannerParams:
    """The planner's thresholds and look model (see the module docstring's tables).

    Distances m, angles rad unless named ``_deg``; sigmas one-sigma.
    """

    confirm_existence: float = 0.9
    confirm_detections: int = 5
    position_2sigma_m: float = 1.0
    look_2sigma_m: float = 0.45
    class_entropy_bits: float = 0.5
    confident_existence: float = 0.99
    leg_start_range_m: float = 12.0
    leg_end_range_m: float = 5.0
    altitude_m: float = 2.0
    range_sigma_m: float = 0.05
    altitude_sigma_m: float = 0.1
    azimuth_sigma_rad: float = 0.015
    aspect_sigma_m: float = 0.3
    reference_bias_sigma_m: float = 0.0
    aspect_bin_deg: float = 30.0
    n_headings: int = 24
    max_legs_per_object: int = 2
    area_margin_m: float = 2.0
    exact_tour_max: int = 7

    def __post_init__(self) -> None:
        if not self.leg_start_range_m > self.leg_end_range_m > 0.0:
            raise ValueError(f"leg_start_range_m ({self.leg_start_range_m}) must exceed leg_end_range_m "
                             f"({self.leg_end_range_m}) > 0")
        if self.n_headings < 4:
            raise ValueError(f"n_headings must be >= 4, got {self.n_headings}")


@dataclass(frozen=True, slots=True)
class InspectionLeg:
    """One planned look: run from ``start_ne_m`` to ``end_ne_m`` (m, NED) on ``heading_rad``
    towards object ``object_id`` at ``object_ne_m``; ``predicted_2sigma_m`` / ``now_2sigma_m``:
    the look covariance's 2-sigma semi-major after / before it."""

    object_id: int
    object_ne_m: tuple[float, float]
    heading_rad: float
    start_ne_m: tuple[float, float]
    end_ne_m: tuple[float, float]
    now_2sigma_m: float
    predicted_2sigma_m: float

    @property
    def length_m(self) -> float:
        return float(math.dist(self.start_ne_m, self.end_ne_m))


@dataclass
class LookRecord:
    """An object's looks grouped into aspects: a look joins the aspect whose first bearing is
    nearest, when within ``aspect_rad`` of it, else starts a new one. Each aspect keeps
    (first bearing rad, shortest ground range m, frames)."""

    aspects: list[tuple[float, float, int]] = field(default_factory=list)
    _cov: FloatArray | None = field(default=None, repr=False, compare=False)

    def add(self, bearing_rad: float, ground_range_m: float, aspect_rad: float, frames: int = 1) -> None:
        best, best_d = -1, math.inf
        for k, (b, _, _) in enumerate(self.aspects):
            d = abs(math.remainder(bearing_rad - b, 2.0 * math.pi))
            if d < best_d:
                best, best_d = k, d
        self._cov = None
        if best < 0 or best_d > aspect_rad:
            self.aspects.append((float(bearing_rad), float(ground_range_m), int(frames)))
            return
        b, g, n = self.aspects[best]
        self.aspects[best] = (b, min(g, float(ground_range_m)), n + int(frames))


def class_entropy_bits(pmf: ArrayLike) -> float:
    """Shannon entropy of a class pmf, bits."""
    p = np.clip(np.asarray(pmf, dtype=float), 0.0, 1.0)
    p = p[p > 0.0]
    return float(-np.sum(p * np.log2(p)))


def semi_major_2sigma_m(cov_2x2: ArrayLike) -> float:
    """2-sigma semi-major axis of a 2x2 covariance, m."""
    return 2.0 * math.sqrt(max(float(np.linalg.eigvalsh(np.asarray(cov_2x2, dtype=float))[-1]), 0.0))


def look_information(params: PlannerParams, bearing_rad: ArrayLike, ground_range_m: ArrayLike) -> FloatArray:
    """(..., 2, 2) horizontal information of a look along ``bearing_rad`` (the line of sight,
    NED rad) at ``ground_range_m``: the flat-seabed geometry of [P000] eq. 6 plus the aspect error."""
    b = np.asarray(bearing_rad, dtype=float)
    g = np.maximum(np.asarray(ground_range_m, dtype=float), 0.5)
    h = params.altitude_m
    r = np.hypot(g, h)
    var_along = (r / g * params.range_sigma_m) ** 2 + (h / g * params.altitude_sigma_m) ** 2 + params.aspect_sigma_m ** 2
    var_across = (g * params.azimuth_sigma_rad) ** 2 + (0.5 * params.aspect_sigma_m) ** 2
    u = np.stack([np.cos(b), np.sin(b)], axis=-1)
    v = np.stack([-np.sin(b), np.cos(b)], axis=-1)
    return (u[..., :, None] * u[..., None, :] / var_along[..., None, None]
            + v[..., :, None] * v[..., None, :] / var_across[..., None, None])


def look_terms(params: PlannerParams, record: LookRecord) -> tuple[FloatArray, FloatArray]:
    """An object's looks as (information (2, 2), bias information (2,)): ``sum_k I_k`` (plus a
    1e-4 m^-2 floor) and ``sum_k I_k u_k``, with ``I_k`` each aspect's
    :func:`look_information` and ``u_k`` its line of sight (unit NE, from the sonar)."""
    info = np.eye(2) * 1e-4
    bias = np.zeros(2)
    if record.aspects:
        b = np.array([v[0] for v in record.aspects])
        g = np.array([v[1] for v in record.aspects])
        info_k = look_information(params, b, g)
        info = info + info_k.sum(axis=0)
        bias = np.einsum("kij,kj->i", info_k, np.stack([np.cos(b), np.sin(b)], axis=-1))
    return info, bias


def covariance_from_terms(params: PlannerParams, info: ArrayLike, bias: ArrayLike) -> FloatArray:
    """(..., 2, 2) look covariance from :func:`look_terms` (stacked along leading axes): the
    fused estimate ``P sum_k I_k z_k`` with ``P = (sum_k I_k)^-1`` moves by ``m = P sum_k I_k u_k``
    per metre of the reference-point bias (the leading edge lies a radius before the centre
    along every line of sight), so ``P + reference_bias_sigma_m^2 m m^T``: looks from opposite
    sides cancel it, looks from one side keep it whole."""
    P = np.linalg.inv(np.asarray(info, dtype=float))
    m = np.einsum("...ij,...j->...i", P, np.asarray(bias, dtype=float))
    return P + params.reference_bias_sigma_m ** 2 * m[..., :, None] * m[..., None, :]


def look_covariance(params: PlannerParams, record: LookRecord) -> FloatArray:
    """(2, 2) look covariance of an object's recorded looks (large when it has none), m^2
    (:func:`covariance_from_terms`; kept on the record until its next look)."""
    if record._cov is not None:
        return record._cov
    record._cov = covariance_from_terms(params, *look_terms(params, record))
    return record._cov


def tour_order(start_ne_m: ArrayLike, legs_start_ne_m: ArrayLike, legs_end_ne_m: ArrayLike,
               exact_max: int = 8) -> list[int]:
    """Visiting order of legs minimising the open tour's transit length from ``start_ne_m``
    ((2,) m) through each leg's start ((n, 2) m) to its end ((n, 2) m): Held-Karp dynamic
    programming for n <= ``exact_max`` (exact), else nearest neighbour then 2-opt moves."""
    s = np.asarray(legs_start_ne_m, dtype=float).reshape(-1, 2)
    e = np.asarray(legs_end_ne_m, dtype=float).reshape(-1, 2)
    n = len(s)
    if n <= 1:
        return list(range(n))
    p0 = np.asarray(start_ne_m, dtype=float)[:2]
    first = np.linalg.norm(s - p0, axis=1)  # (n,)
    between = np.linalg.norm(e[:, None, :] - s[None, :, :], axis=2)  # i's end -> j's start
    if n <= exact_max:
        return _held_karp(first, between)
    order = [int(np.argmin(first))]
    left = set(range(n)) - {order[0]}
    while left:
        last = order[-1]
        nxt = min(left, key=lambda j: between[last, j])
        order.append(nxt)
        left.remove(nxt)
    return _two_opt(order, first, between)


def tour_length_m(order: Sequence[int], first: FloatArray, between: FloatArray) -> float:
    """Transit length of an open tour (leg lengths excluded: they are the same in any order)."""
    if not order:
        return 0.0
    return float(first[order[0]] + sum(between[a, b] for a, b in zip(order[:-1], order[1:])))


def _held_karp(first: FloatArray, between: FloatArray) -> list[int]:
    n = len(first)
    full = 1 << n
    cost = np.full((full, n), np.inf)
    parent = np.full((full, n), -1, dtype=np.int64)
    cost[1 << np.arange(n), np.arange(n)] = first
    bits = 1 << np.arange(n)
    for mask in range(1, full):
        row = cost[mask]
        ends = np.nonzero(np.isfinite(row))[0]
        if not ends.size:
            continue
        outside = np.nonzero((mask & bits) == 0)[0]
        if not outside.size:
            continue
        cand = row[ends][:, None] + between[np.ix_(ends, outside)]  # (ends, outside)
        k = np.argmin(cand, axis=0)
        best = cand[k, np.arange(len(outside))]
        new = mask | bits[outside]
        better = best < cost[new, outside]
        cost[new[better], outside[better]] = best[better]
        parent[new[better], outside[better]] = ends[k[better]]
    mask, j = full - 1, int(np.argmin(cost[full - 1]))
    order = []
    while j >= 0:
        order.append(j)
        prev = int(parent[mask, j])
        mask ^= 1 << j
        j = prev
    return order[::-1]


def _two_opt(order: list[int], first: FloatArray, between: FloatArray) -> list[int]:
    """2-opt on the open, asymmetric tour: every reversal ``order[i..k]`` is scored at once from
    prefix sums of the forward and backward edge costs; the best improving one is applied."""
    arr = np.asarray(order, dtype=np.int64)
    n = len(arr)
    i_idx, k_idx = np.triu_indices(n, 1)
    while True:
        fwd = between[arr[:-1], arr[1:]]  # edge t: arr[t] -> arr[t+1]
        bwd = between[arr[1:], arr[:-1]]  # the same edge reversed
        cf = np.concatenate([[0.0], np.cumsum(fwd)])
        cb = np.concatenate([[0.0], np.cumsum(bwd)])
        inner_old = cf[k_idx] - cf[i_idx]
        inner_new = cb[k_idx] - cb[i_idx]
        head_old = np.where(i_idx == 0, first[arr[0]], between[arr[np.maximum(i_idx - 1, 0)], arr[i_idx]])
        head_new = np.where(i_idx == 0, first[arr[k_idx]], between[arr[np.maximum(i_idx - 1, 0)], arr[k_idx]])
        last = k_idx == n - 1
        kp1 = np.minimum(k_idx + 1, n - 1)
        tail_old = np.where(last, 0.0, between[arr[k_idx], arr[kp1]])
        tail_new = np.where(last, 0.0, between[arr[i_idx], arr[kp1]])
        gain = (head_old + inner_old + tail_old) - (head_new + inner_new + tail_new)
        j = int(np.argmax(gain))
        if not gain[j] > 1e-9:
            return [int(v) for v in arr]
        i, k = int(i_idx[j]), int(k_idx[j])
        arr[i:k + 1] = arr[i:k + 1][::-1].copy()


class InspectionPlanner:
    """Plans inspection legs over the world model (see the module docstring).

    Args:
        params: thresholds and look model.
        area: the survey area legs must stay in (grown by ``params.area_margin_m``).

    Call :meth:`observe` at every world-model update with the vehicle's navigation position
    (to record the looks), then :meth:`plan` for the legs to fly, in order.
    """

    def __init__(self, params: PlannerParams, area: SurveyArea) -> None:
        self.params = params
        self.area = area
        self.looks: dict[int, LookRecord] = {}
        self.legs_flown: dict[int, int] = {}
        self.nav_cov_ne_m2 = np.zeros((2, 2))
        self._n_det: dict[int, int] = {}
        self._bin_rad = math.radians(params.aspect_bin_deg)
        self._headings = np.arange(params.n_headings) * (2.0 * math.pi / params.n_headings)

    def reset(self) -> None:
        self.nav_cov_ne_m2 = np.zeros((2, 2))
        self.looks.clear()
        self.legs_flown.clear()
        self._n_det.clear()

    # -- bookkeeping ------------------------------------------------------------------
    def observe(self, objects: Sequence, vehicle_ne_m: ArrayLike) -> None:
        """Record a look at every object whose detection count grew since the last call:
        the bearing and ground range from ``vehicle_ne_m`` ((2,) m, the navigation estimate)."""
        p = np.asarray(vehicle_ne_m, dtype=float)[:2]
        for o in objects:
            n_old = self._n_det.get(o.id, 0)
            if o.n_detections > n_old:
                d = np.asarray(o.pos_ned, dtype=float)[:2] - p
                self.looks.setdefault(o.id, LookRecord()).add(math.atan2(d[1], d[0]), float(np.hypot(*d)),
                                                              self._bin_rad, o.n_detections - n_old)
            self._n_det[o.id] = int(o.n_detections)

    def set_navigation_covariance(self, cov_ne_m2: ArrayLike) -> None:
        """The vehicle's horizontal position covariance now ((2, 2) m^2, north-east; from the
        navigation estimate): the part of every world-model ellipse that looks cannot shrink."""
        self.nav_cov_ne_m2 = np.asarray(cov_ne_m2, dtype=float)[:2, :2].copy()

    def reducible_2sigma_m(self, obj) -> float:
        """2-sigma semi-major of the world-model ellipse less the navigation covariance
        (eigenvalues clipped at 0), m: what further looks can shrink."""
        c = np.asarray(obj.cov_ned, dtype=float)[:2, :2] - self.nav_cov_ne_m2
        w = np.linalg.eigvalsh(0.5 * (c + c.T))
        return 2.0 * math.sqrt(max(float(w[-1]), 0.0))

    def leg_flown(self, object_id: int) -> None:
        """Count a finished inspection leg of ``object_id`` (at most ``max_legs_per_object``)."""
        self.legs_flown[object_id] = self.legs_flown.get(object_id, 0) + 1

    # -- judgement ----------------------------------------------------------------------
    def confirmed(self, obj) -> bool:
        p = self.params
        return obj.existence_probability >= p.confirm_existence and obj.n_detections >= p.confirm_detections

    def in_area(self, obj) -> bool:
        """Whether the object lies in the survey area grown by ``area_margin_m``."""
        return bool(self.area.contains(np.asarray(obj.pos_ned, dtype=float)[:2], self.params.area_margin_m))

    def look_2sigma_m(self, obj) -> float:
        return semi_major_2sigma_m(look_covariance(self.params, self.looks.get(obj.id, LookRecord())))

    def reasons(self, obj) -> list[str]:
        """Why a confirmed object is not yet confident (empty: confident)."""
        p = self.params
        out = []
        if self.reducible_2sigma_m(obj) > p.position_2sigma_m:
            out.append("position")
        if self.look_2sigma_m(obj) > p.look_2sigma_m:
            out.append("look geometry")
        if class_entropy_bits(obj.class_pmf) > p.class_entropy_bits:
            out.append("class")
        if obj.existence_probability < p.confident_existence:
            out.append("existence")
        return out

    def confident(self, obj) -> bool:
        return not self.reasons(obj)

    def candidates(self, objects: Sequence, refine: bool = False) -> list:
        """Confirmed, not confident objects with legs left, in the world model's order
        (``refine``: confident ones too, to use a time budget that is left)."""
        p = self.params
        return [o for o in objects if self.confirmed(o) and self.in_area(o) and (refine or not self.confident(o))
                and self.legs_flown.get(o.id, 0) < p.max_legs_per_object]

    def map_confident(self, objects: Sequence) -> bool:
        """Every confirmed object in the area is confident."""
        return all(self.confident(o) for o in objects if self.confirmed(o) and self.in_area(o))

    # -- planning -----------------------------------------------------------------------
    def best_leg(self, obj) -> InspectionLeg | None:
        """The leg towards ``obj`` whose heading most shrinks its look covariance, staying in
        the area; None when every heading leaves it."""
        return self.best_legs([obj])[0]

    def best_legs(self, objects: Sequence) -> list[InspectionLeg | None]:
        """:meth:`best_leg` of each object, computed together."""
        p = self.params
        if not objects:
            return []
        terms = [look_terms(p, self.looks.get(o.id, LookRecord())) for o in objects]
        info = np.array([t[0] for t in terms])  # (m, 2, 2)
        bias = np.array([t[1] for t in terms])  # (m, 2)
        covs = covariance_from_terms(p, info, bias)  # (m, 2, 2): each object's look covariance now
        g_mean = 0.5 * (p.leg_start_range_m + p.leg_end_range_m)
        heads = self._headings
        u = np.stack([np.cos(heads), np.sin(heads)], axis=1)  # (h, 2): the new look's line of sight
        new_info = look_information(p, heads, np.full(len(heads), g_mean))  # (h, 2, 2)
        post = covariance_from_terms(p, info[:, None] + new_info[None],
                                     bias[:, None] + np.einsum("hij,hj->hi", new_info, u)[None])  # (m, h, 2, 2)
        a, b, d = post[..., 0, 0], post[..., 0, 1], post[..., 1, 1]
        lam = 0.5 * (a + d) + np.sqrt(0.25 * (a - d) ** 2 + b * b)  # the largest eigenvalue
        obj_ne = np.array([np.asarray(o.pos_ned, dtype=float)[:2] for o in objects])  # (m, 2)
        starts = obj_ne[:, None] - p.leg_start_range_m * u[None]
        ends = obj_ne[:, None] - p.leg_end_range_m * u[None]
        inside = self.area.contains(starts, p.area_margin_m) & self.area.contains(ends, p.area_margin_m)
        ks = np.argmin(np.where(inside, lam, np.inf), axis=1)
        out: list[InspectionLeg | None] = []
        for i, o in enumerate(objects):
            k = int(ks[i])
            if not inside[i, k]:
                out.append(None)
                continue
            out.append(InspectionLeg(int(o.id), (float(obj_ne[i, 0]), float(obj_ne[i, 1])), float(heads[k]),
                                     (float(starts[i, k, 0]), float(starts[i, k, 1])),
                                     (float(ends[i, k, 0]), float(ends[i, k, 1])),
                                     semi_major_2sigma_m(covs[i]), 2.0 * math.sqrt(float(lam[i, k]))))
        return out

    def _flipped(self, leg: InspectionLeg) -> InspectionLeg | None:
        """The same leg flown the other way, when that gives the same information (no
        reference-point bias in the look model) and stays in the area; else None."""
        p = self.params
        if p.reference_bias_sigma_m > 0.0:
            return None
        h = leg.heading_rad + math.pi
        u = np.array([math.cos(h), math.sin(h)])
        o = np.asarray(leg.object_ne_m)
        s, e = o - p.leg_start_range_m * u, o - p.leg_end_range_m * u
        if not (self.area.contains(s, p.area_margin_m) and self.area.contains(e, p.area_margin_m)):
            return None
        return InspectionLeg(leg.object_id, leg.object_ne_m, float(math.remainder(h, 2.0 * math.pi)),
                             (float(s[0]), float(s[1])), (float(e[0]), float(e[1])), leg.now_2sigma_m,
                             leg.predicted_2sigma_m)

    def plan(self, objects: Sequence, vehicle_ne_m: ArrayLike, refine: bool = False) -> list[InspectionLeg]:
        """The legs to fly from ``vehicle_ne_m`` ((2,) m), in tour order (empty: nothing to
        inspect); ``refine``: as :meth:`candidates`."""
        legs = [leg for leg in self.best_legs(self.candidates(objects, refine)) if leg is not None]
        if not legs:
            return []
        pos = np.asarray(vehicle_ne_m, dtype=float)[:2]
        # each leg's direction: the one (of the two with the same information) nearer the vehicle
        legs = [min((leg, self._flipped(leg)), key=lambda lg: math.inf if lg is None
                    else float(np.hypot(*(np.asarray(lg.start_ne_m) - pos)))) for leg in legs]
        order = tour_order(pos, [lg.start_ne_m for lg in legs], [lg.end_ne_m for lg in legs],
                           self.params.exact_tour_max)
        out: list[InspectionLeg] = []
        here = pos
        for i in order:  # then re-pick each direction along the tour
            leg = legs[i]
            alt = self._flipped(leg)
            if alt is not None and np.hypot(*(np.asarray(alt.start_ne_m) - here)) < np.hypot(*(np.asarray(leg.start_ne_m) - here)):
                leg = alt
            out.append(leg)
            here = np.asarray(leg.end_ne_m)
        return out


def brute_force_order(start_ne_m: ArrayLike, legs_start_ne_m: ArrayLike, legs_end_ne_m: ArrayLike) -> list[int]:
    """Shortest open tour by trying every order (the oracle of :func:`tour_order` in tests; n <= 8)."""
    s = np.asarray(legs_start_ne_m, dtype=float).reshape(-1, 2)
    e = np.asarray(legs_end_ne_m, dtype=float).reshape(-1, 2)
    p0 = np.asarray(start_ne_m, dtype=float)[:2]
    first = np.linalg.norm(s - p0, axis=1)
    between = np.linalg.norm(e[:, None, :] - s[None, :, :], axis=2)
    return list(min(itertools.permutations(range(len(s))), key=lambda o: tour_length_m(o, first, between)))


__all__ = ["InspectionLeg", "InspectionPlanner", "LookRecord", "PlannerParams", "SurveyArea", "brute_force_order",
           "class_entropy_bits", "covariance_from_terms", "look_covariance", "look_information", "look_terms",
           "semi_major_2sigma_m", "tour_order", "tour_length_m"]
