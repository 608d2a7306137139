"""PMHA world model against exhaustive enumeration and synthetic detection streams."""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest

from autonomy.localization import LocalizedDetection
from autonomy.world_model import PMHA
from autonomy.world_model.anchor import class_update, class_update_batch
from autonomy.world_model.config import WorldModelConfig
from sim.evaluation.world_model_score import score_world_model

TRUTHS = np.array([[0, 10, 4], [0, 20, 4], [0, 25, 4], [-8, 10, 4], [-7, 15, 4], [-8, 22, 4]], float)
REGION = ([-20.0, 0.0, 3.0], [10.0, 35.0, 5.0])


def _z(t, pos, score=0.8, var=0.09):
    return LocalizedDetection(t, np.asarray(pos, float), var * np.eye(3), score)


# ---------------------------------------------------------------- exhaustive enumeration
def _brute_force(scans, cfg, volume, visible):
    """Posterior over worlds by enumerating every origin of every measurement.

    Independent of the PMHA code: plain Kalman filter and the hypothesis factor written out.
    Returns {frozenset of measurement-id histories: probability}.
    """
    log_u = -math.log(volume)
    paths = [(0.0, [])]  # (log weight, objects: list of dict(x, P, t, pmf, ids))
    uid = 0
    for t, zs in scans:
        new_paths = []
        ids = list(range(uid, uid + len(zs)))
        uid += len(zs)
        for logw, objs in paths:
            n_obj = len(objs)
            labels = ["C", "N"] + list(range(n_obj))
            for combo in itertools.product(labels, repeat=len(zs)):
                used = [c for c in combo if not isinstance(c, str)]
                if len(used) != len(set(used)):
                    continue
                lw = logw
                out = [dict(o) for o in objs]
                for k, o in enumerate(objs):
                    P = o["P"] + cfg.process_noise_m2_per_s * (t - o["t"]) * np.eye(3)
                    if t - o["t"] > cfg.kf_timeout_s:
                        P = cfg.fallback_cov_m2 * np.eye(3)
                    pd = cfg.p_detect * max(float(visible(o["x"][None])[0]), cfg.visibility_floor)
                    if k not in used:
                        lw += math.log(1.0 - pd)
                        continue
                    if pd == 0.0:  # an anchor outside the fan cannot be detected
                        lw = -math.inf
                        break
                    j = combo.index(k)
                    z, R = zs[j].pos_ned, zs[j].cov_ned
                    S = P + R
                    d = z - o["x"]
                    lw += (math.log(cfg.p_existing * pd)
                           - 0.5 * (d @ np.linalg.solve(S, d) + math.log(np.linalg.det(2 * np.pi * S))))
                    q = np.array([zs[j].class_score, 1 - zs[j].class_score])
                    lw += math.log(o["pmf"] @ q)
                    K = P @ np.linalg.inv(S)
                    pmf = o["pmf"] * q
                    out[k] = dict(x=o["x"] + K @ d, P=(np.eye(3) - K) @ P, t=t, pmf=pmf / pmf.sum(),
                                  ids=o["ids"] + (ids[j],))
                for j, c in enumerate(combo):
                    if c == "C":
                        lw += math.log(cfg.p_clutter) + log_u + math.log(0.5)
                    elif c == "N":
                        lw += math.log(cfg.p_new) + log_u + math.log(0.5)
                        q = np.array([zs[j].class_score, 1 - zs[j].class_score])
                        out.append(dict(x=zs[j].pos_ned.copy(), P=zs[j].cov_ned.copy(), t=t, pmf=q,
                                        ids=(ids[j],)))
                if lw > -math.inf:
                    new_paths.append((lw, out))
        paths = new_paths
    lws = np.array([p[0] for p in paths])
    probs = np.exp(lws - lws.max())
    probs /= probs.sum()
    out = {}
    for p, (_, objs) in zip(probs, paths):
        key = frozenset(o["ids"] for o in objs)
        out[key] = out.get(key, 0.0) + p
    return out


def test_hypothesis_probabilities_equal_exhaustive_enumeration():
    cfg = WorldModelConfig(max_hypotheses=100_000, prune_ratio=1e-300, drop_tentative_after_s=None,
                           gate_mahalanobis2=1e6, process_noise_m2_per_s=0.05, kf_timeout_s=1.5,
                           visibility_floor=0.1, scan_cluster_mahalanobis2=None)  # point measurements
    lo, hi = np.array(REGION[0]), np.array(REGION[1])
    volume = float(np.prod(hi - lo))

    def visible(p):  # the fan covers north > -5 only
        return p[:, 0] > -5.0

    scans = [
        (0.0, [_z(0.0, [0, 10, 4], 0.9), _z(0.0, [0.6, 10.4, 4.1], 0.6)]),
        (1.0, [_z(1.0, [0.2, 10.1, 4.0], 0.8), _z(1.0, [-8, 10, 4], 0.7)]),
        (3.0, [_z(3.0, [0.1, 9.8, 4.0], 0.7), _z(3.0, [-7.5, 10.3, 4.2], 0.9)]),
        (3.5, [_z(3.5, [0.3, 10.3, 4.0], 0.8)]),
    ]
    pmha = PMHA(cfg, region_ned=REGION)
    for t, zs in scans:
        pmha.update(t, zs, visible)
    expected = _brute_force(scans, cfg, volume, visible)
    got = {frozenset(a.measurement_ids for a in h.anchors): h.probability for h in pmha.hypotheses}
    assert len(expected) > 500
    assert set(got) == set(expected)
    for key, p in expected.items():
        assert got[key] == pytest.approx(p, rel=1e-7, abs=1e-15)


def test_k_best_expansion_returns_the_top_k_of_the_exhaustive_set():
    full_cfg = WorldModelConfig(max_hypotheses=100_000, prune_ratio=1e-300, drop_tentative_after_s=None,
                                scan_cluster_mahalanobis2=None)
    k_cfg = full_cfg.model_copy(update={"max_hypotheses": 10, "merge_mahalanobis2": None})
    scans = [(0.0, [_z(0.0, [0, 10, 4])]),
             (0.5, [_z(0.5, [0.1, 10.2, 4]), _z(0.5, [0.4, 10, 4]), _z(0.5, [-8, 10, 4])])]
    full, k = PMHA(full_cfg, REGION), PMHA(k_cfg, REGION)
    for t, zs in scans:
        full.update(t, zs)
        k.update(t, zs)
    assert len(full.hypotheses) > 20
    top_full = full.hypotheses[:10]
    got = k.hypotheses
    assert [frozenset(a.measurement_ids for a in h.anchors) for h in got] == [
        frozenset(a.measurement_ids for a in h.anchors) for h in top_full
    ]
    total = sum(h.probability for h in top_full)
    np.testing.assert_allclose([h.probability for h in got], [h.probability / total for h in top_full])


def test_singletons_are_filtered_as_clutter():
    pmha = PMHA(WorldModelConfig(), REGION)
    pmha.update(0.0, [_z(0.0, [0, 10, 4], 0.95)])
    assert pmha.hypotheses[0].anchors == ()  # p_clutter > p_new: best world has no object
    assert pmha.world_model(min_detections=1) == []
    pmha.update(0.3, [_z(0.3, [0.1, 10.1, 4], 0.95)])  # confirmed by a second detection
    wm = pmha.world_model()
    assert len(wm) == 1 and wm[0].n_detections == 2


def _lawnmower_stream(seed, n_scans=240, p_detect=0.8, clutter_rate=0.4, sigma=0.3):
    """Detections of TRUTHS seen by a fan sweeping north->south legs, plus uniform clutter."""
    rng = np.random.default_rng(seed)
    scans = []
    for k in range(n_scans):
        t = k / 3.0
        leg = (k // 60) % 2
        east = 5.0 + 30.0 * ((k % 60) / 60.0 if leg == 0 else 1.0 - (k % 60) / 60.0)
        window = (east - 2.0, east + 8.0) if leg == 0 else (east - 8.0, east + 2.0)

        def visible(p, w=window):
            return (p[:, 1] >= w[0]) & (p[:, 1] <= w[1])

        zs = []
        for x in TRUTHS[visible(TRUTHS)]:
            if rng.random() < p_detect:
                zs.append(_z(t, x + rng.normal(0, sigma, 3), rng.uniform(0.6, 0.95), sigma**2))
        for _ in range(rng.poisson(clutter_rate)):
            c = np.array([rng.uniform(-20, 10), rng.uniform(*window), rng.uniform(3, 5)])
            zs.append(_z(t, c, rng.uniform(0.5, 0.8), sigma**2))
        scans.append((t, zs, visible))
    return scans


@pytest.mark.parametrize("seed", [0, 1])
def test_cardinality_converges_to_truth_with_clutter_and_misses(seed):
    pmha = PMHA(WorldModelConfig(p_detect=0.8), REGION)
    counts = []
    for t, zs, visible in _lawnmower_stream(seed):
        pmha.update(t, zs, visible)
        counts.append(len(pmha.world_model()))
    assert counts[-1] == len(TRUTHS)
    assert all(c == len(TRUTHS) for c in counts[-30:])
    est = np.array([o.pos_ned for o in pmha.world_model()])
    s = score_world_model(est, TRUTHS)
    assert s["matched"] == 6 and s["false"] == 0
    assert s["mean_position_error_m"] < 0.15


@pytest.mark.parametrize("floor", [0.0, 0.05])
def test_invisible_anchor_is_not_penalised_for_missed_detections(floor):
    def run(visible_later):
        pmha = PMHA(WorldModelConfig(visibility_floor=floor), REGION)
        pmha.update(0.0, [_z(0.0, [0, 10, 4])])
        pmha.update(0.3, [_z(0.3, [0, 10, 4])])
        for k in range(10):
            pmha.update(1.0 + k, [], lambda p: np.full(len(p), visible_later))
        return pmha.world_model()

    assert len(run(False)) == 1  # out of the fan: no evidence against it
    assert run(True) == []  # in the fan and never seen again: not an object


def test_kf_falls_back_to_fixed_gaussian_after_timeout():
    cfg = WorldModelConfig(kf_timeout_s=5.0, fallback_cov_m2=2.0, process_noise_m2_per_s=0.01)
    predictor = PMHA(cfg).predictor
    np.testing.assert_allclose(predictor.predict_covar(0.1 * np.eye(3), 4.0), 0.14 * np.eye(3))
    np.testing.assert_allclose(predictor.predict_covar(0.1 * np.eye(3), 6.0), 2.0 * np.eye(3))


def test_class_pmf_follows_atr_scores():
    pmha = PMHA(WorldModelConfig(), REGION)
    for k in range(5):
        pmha.update(0.3 * k, [_z(0.3 * k, [0, 10, 4], 0.8)])
    (obj,) = pmha.world_model()
    assert obj.class_name == "target"
    assert obj.class_pmf[0] == pytest.approx(0.8**5 / (0.8**5 + 0.2**5))


def test_runs_are_deterministic():
    def run():
        pmha = PMHA(WorldModelConfig(p_detect=0.8), REGION)
        for t, zs, visible in _lawnmower_stream(5, n_scans=90):
            pmha.update(t, zs, visible)
        return json.dumps(pmha.to_json(), sort_keys=True)

    assert run() == run()


def test_bad_input_is_rejected():
    with pytest.raises(ValueError, match="p_new"):
        WorldModelConfig(p_new=0.5)
    with pytest.raises(ValueError, match="region_ned"):
        PMHA(WorldModelConfig(), ([0, 0, 0], [1, 1, 0]))
    pmha = PMHA(WorldModelConfig())
    pmha.update(1.0, [])
    with pytest.raises(ValueError, match="backwards"):
        pmha.update(0.5, [])


def test_no_new_objects_outside_the_surveyed_region():
    """Repeated detections of a structure outside the surveyed volume stay clutter, while
    the same stream inside it becomes an object; an object inside keeps its anchor when
    later measurements straddle the region edge."""
    region = ((-10.0, -10.0, 0.0), (10.0, 10.0, 5.0))
    outside = [[_z(t, [30.0, 0.0, 4.0])] for t in range(20)]
    pmha = PMHA(WorldModelConfig(), region_ned=region)
    for t, scan in enumerate(outside):
        pmha.update(float(t), scan)
    assert pmha.world_model() == []
    inside = [[_z(t, [9.8, 0.0, 4.0])] for t in range(20)]
    pmha = PMHA(WorldModelConfig(), region_ned=region)
    for t, scan in enumerate(inside):
        pmha.update(float(t), scan)
    assert len(pmha.world_model()) == 1
    edge = [[_z(20 + t, [10.2, 0.0, 4.0])] for t in range(5)]
    for t, scan in enumerate(edge):
        pmha.update(20.0 + t, scan)
    objs = pmha.world_model()
    assert len(objs) == 1 and objs[0].n_detections == 25


def _hypotheses_bits(pmha):
    return [
        (h.probability.hex(), [(a.id, a.version, a.n_detections, a.measurement_ids, a.t_last_s,
                                a.pos_ned.tobytes(), a.cov_ned.tobytes(), a.class_pmf.tobytes()) for a in h.anchors])
        for h in pmha.hypotheses
    ]


@pytest.mark.parametrize("max_hypotheses", [5, 100])
def test_batched_posteriors_equal_one_pair_at_a_time(monkeypatch, max_hypotheses):
    """The Kalman and class posteriors of all gated pairs, computed in one batch, give the
    same hypotheses bit for bit as updating each drawn pair alone (the plain path, also the
    fallback when a batch fails)."""
    def run():
        pmha = PMHA(WorldModelConfig(p_detect=0.8, max_hypotheses=max_hypotheses), REGION)
        out = []
        for t, zs, visible in _lawnmower_stream(3, n_scans=90):
            pmha.update(t, zs, visible)
            out.append(_hypotheses_bits(pmha))
        return out

    batched = run()
    monkeypatch.setattr(PMHA, "_posteriors", lambda self, *args: {})
    assert run() == batched
    assert len(batched[-1]) > 1 and any(len(h[1]) > 1 for h in batched[-1])


def test_batched_class_update_is_bit_identical():
    rng = np.random.default_rng(0)
    pmf = rng.dirichlet([1.0, 1.0], 500)
    lik = rng.uniform(0.01, 0.99, (500, 1)) * [1.0, -1.0] + [0.0, 1.0]
    batch = class_update_batch(pmf, lik)
    assert all(np.array_equal(class_update(p, q), b) for p, q, b in zip(pmf, lik, batch))


def _shared_stream(rng, looks, q=7):
    """One object seen ``looks`` times from a drifting pose: the detections share one
    navigation / reference-point error draw u through slowly changing sensitivities L_k."""
    x_true = np.array([0.0, 15.0, 4.0])
    u = rng.normal(size=q)
    A, B = rng.normal(scale=0.12, size=(3, q)), rng.normal(scale=0.0015, size=(3, q))
    scans = []
    for k in range(looks):
        L = A + k * B
        Rv = 0.02 * np.eye(3)
        z = x_true + L @ u + rng.multivariate_normal(np.zeros(3), Rv)
        scans.append(LocalizedDetection(0.5 * k, z, Rv + L @ L.T, 0.9, shared_ned=L))
    return x_true, scans


@pytest.mark.parametrize("consider", [True, False])
def test_world_model_ellipses_hold_the_shared_navigation_error(consider):
    # Monte Carlo over runs: horizontal NEES of the one object against its true position.
    # Consistent (mean 2, chi-square band of 150 runs) with the consider terms; without them
    # repeated looks shrink the ellipse far below the error they share.
    from sim.evaluation.nees import horizontal_nees, mean_nees_band

    rng = np.random.default_rng(11)
    cfg = WorldModelConfig(consider_shared_errors=consider, process_noise_m2_per_s=0.0)  # the model the stream follows
    nees, n_objects = [], []
    for _ in range(150):
        x_true, scans = _shared_stream(rng, 25)
        wm = PMHA(cfg, region_ned=([-10.0, 5.0, -2.0], [10.0, 25.0, 10.0]))
        for z in scans:
            wm.update(z.t_s, [z])
        objs = wm.world_model()
        n_objects.append(len(objs))
        obj = max(objs, key=lambda o: o.n_detections)
        nees.append(horizontal_nees(obj.pos_ned[:2] - x_true[:2], obj.cov_ned[:2, :2]))
    lo, hi = mean_nees_band(len(nees), 2)
    # a consistent model splits an object only on a rare innovation past the gate
    assert np.mean(np.array(n_objects) == 1) >= 0.98, np.bincount(n_objects)
    if consider:
        assert lo <= np.mean(nees) <= hi, (np.mean(nees), lo, hi)
    else:
        assert np.mean(nees) > 3 * hi, np.mean(nees)


def test_two_well_measured_objects_a_few_decimetres_apart_are_not_joined_as_duplicates():
    """The duplicate test joins anchors only where their estimates are one object's: two
    objects 0.3 m apart, each seen every scan with 2 cm noise, stay two (their difference is
    hundreds of sigmas)."""
    rng = np.random.default_rng(0)
    a, b = np.array([0.0, 10.0, 4.0]), np.array([0.0, 10.3, 4.0])
    pmha = PMHA(WorldModelConfig(), region_ned=REGION)
    for k in range(20):
        zs = [_z(k, p + rng.normal(0.0, 0.02, 3), var=0.0004) for p in (a, b)]
        pmha.update(float(k), zs, lambda x: np.ones(len(x)))
    objects = pmha.world_model()
    assert len(objects) == 2
    est = sorted(o.pos_ned[1] for o in objects)
    assert est[0] == pytest.approx(10.0, abs=0.03) and est[1] == pytest.approx(10.3, abs=0.03)


def test_an_objects_existence_counts_the_worlds_that_hold_it_under_any_symbol():
    """A world where one detection of an object was clutter starts its anchor a detection
    later, under another symbol, at the same place. The reported existence is the probability
    of the worlds holding an anchor at the object (counted here by distance, independently of
    the duplicate test), not only the reported symbol's: on the clutter stream the two differ
    by up to ~0.5 early on, and the reported one follows the worlds."""
    pmha = PMHA(WorldModelConfig(p_detect=0.8), REGION)
    own_short = 0.0
    for t, zs, visible in _lawnmower_stream(0):
        pmha.update(t, zs, visible)
        worlds = pmha.hypotheses
        for o in pmha.world_model():
            held = sum(h.probability for h in worlds if any(np.linalg.norm(a.pos_ned - o.pos_ned) < 0.5
                                                            for a in h.anchors))
            own = sum(h.probability for h in worlds if any(a.id == o.id for a in h.anchors))
            assert o.existence_probability == pytest.approx(held, abs=0.01)
            own_short = max(own_short, held - own)
    assert own_short > 0.3  # the symbol's own probability alone would be far off
