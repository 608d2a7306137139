"""Births must not starve and duplicates must not become objects when the hypothesis budget fills.

Synthetic stream: k static objects 3 m apart on a flat floor (z = 4 m), each detected once
per scan (sigma 5 cm horizontally, 2 cm vertically, target score 0.8, three scans a second)
and, with probability p, a second time in the same scan (two boxes on one object). From
scan 10 a new object C, 10 m away, is detected once per scan for 50 scans.
"""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.localization import LocalizedDetection
from autonomy.world_model import PMHA
from autonomy.world_model.config import WorldModelConfig

SIGMA_M = np.array([0.05, 0.05, 0.02])
COV = np.diag(SIGMA_M**2)
C_POS = np.array([10.0, 0.0, 4.0])
C_FIRST_SCAN = 10


def _scans(k: int, p: float, seed: int, n_scans: int = C_FIRST_SCAN + 50):
    rng = np.random.default_rng(seed)
    objects = np.array([[0.0, 3.0 * i, 4.0] for i in range(k)])
    for s in range(n_scans):
        t = s / 3.0
        zs = []
        for x in objects:
            zs.append(LocalizedDetection(t, x + rng.normal(0.0, SIGMA_M), COV, 0.8))
            if rng.random() < p:
                zs.append(LocalizedDetection(t, x + rng.normal(0.0, SIGMA_M), COV, 0.8))
        if s >= C_FIRST_SCAN:
            zs.append(LocalizedDetection(t, C_POS + rng.normal(0.0, SIGMA_M), COV, 0.8))
        yield s, t, zs


def _run(cfg: WorldModelConfig, k: int, p: float, seed: int = 0, n_scans: int = C_FIRST_SCAN + 50):
    pmha = PMHA(cfg)
    born = None
    for s, t, zs in _scans(k, p, seed, n_scans):
        pmha.update(t, zs)
        if born is None and any(np.linalg.norm(o.pos_ned - C_POS) < 0.5 for o in pmha.world_model()):
            born = s
    return born, pmha


@pytest.mark.parametrize("k", [1, 3, 6, 12])
@pytest.mark.parametrize("p", [0.0, 0.3, 1.0])
def test_new_object_is_born_and_duplicates_do_not_become_objects(k, p):
    born, pmha = _run(WorldModelConfig(), k, p)
    assert born is not None and born <= C_FIRST_SCAN + 4, f"C born at scan {born}"
    objects = pmha.world_model()
    assert len(objects) == k + 1
    truth = np.vstack([[[0.0, 3.0 * i, 4.0] for i in range(k)], C_POS])
    err = np.linalg.norm(np.array([o.pos_ned for o in objects])[:, None] - truth[None], axis=-1).min(axis=0)
    assert np.all(err < 0.1)


def test_merging_near_identical_worlds_keeps_the_birth_in_a_small_budget():
    """With point measurements (no same-scan clustering) the duplicates multiply
    near-identical worlds; merging them when the budget is full keeps room for C's world,
    while the plain top-k budget starves it."""
    point = WorldModelConfig(scan_cluster_mahalanobis2=None, max_hypotheses=20)
    born_merged, _ = _run(point, 6, 0.3, n_scans=C_FIRST_SCAN + 15)
    born_plain, _ = _run(point.model_copy(update={"merge_mahalanobis2": None}), 6, 0.3, n_scans=C_FIRST_SCAN + 15)
    assert born_merged is not None and born_merged <= C_FIRST_SCAN + 4
    assert born_plain is None


def test_same_scan_clusters_enter_as_one_fused_measurement():
    """PMHA with clustering equals PMHA with point measurements fed the fused scan
    (information-weighted mean, mean covariance, mean score), computed here by hand."""
    R1, R2 = np.diag([0.01, 0.02, 0.005]), np.diag([0.02, 0.01, 0.005])
    z1, z2 = np.array([0.0, 10.0, 4.0]), np.array([0.1, 9.9, 4.02])
    far = np.array([-8.0, 10.0, 4.0])
    scans = [[LocalizedDetection(0.3 * s, z1 + 0.01 * s, R1, 0.9), LocalizedDetection(0.3 * s, far, R1, 0.6),
              LocalizedDetection(0.3 * s, z2 + 0.01 * s, R2, 0.7)] for s in range(4)]
    W1, W2 = np.linalg.inv(R1), np.linalg.inv(R2)
    fused = [[LocalizedDetection(zs[0].t_s, np.linalg.solve(W1 + W2, W1 @ zs[0].pos_ned + W2 @ zs[2].pos_ned),
                                 0.5 * (R1 + R2), 0.8), zs[1]] for zs in scans]
    clustered = PMHA(WorldModelConfig(drop_tentative_after_s=None))
    point = PMHA(WorldModelConfig(drop_tentative_after_s=None, scan_cluster_mahalanobis2=None))
    for zs, fz in zip(scans, fused):
        clustered.update(zs[0].t_s, zs)
        point.update(fz[0].t_s, fz)
    got, want = clustered.hypotheses, point.hypotheses
    assert len(got) == len(want) > 1
    for g, w in zip(got, want):
        assert g.probability == pytest.approx(w.probability, rel=1e-9)
        for a, b in zip(g.anchors, w.anchors):
            np.testing.assert_allclose(a.pos_ned, b.pos_ned, rtol=0, atol=1e-12)
            np.testing.assert_allclose(a.cov_ned, b.cov_ned, rtol=0, atol=1e-15)
