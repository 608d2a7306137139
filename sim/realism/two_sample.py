"""Classifier two-sample tests: can a classifier tell real patches from simulated ones?

A classifier is trained to separate the two sets and scored on patches it did not see, the
frames split into folds so that no frame gives patches to both sides of a split (Lopez-Paz and
Oquab's classifier two-sample test, [LopezPaz2017] in ``docs/references.md``). Held-out
accuracy 0.5 means the classifier cannot tell the sets apart; 1.0 that it always can. The
sets are balanced by subsampling the larger before the folds are made.

Judges: logistic regression and gradient-boosted trees (scikit-learn, the ``realism`` extra)
on :data:`PATCH_FEATURES` (30 statistics of each patch), and optionally a small CNN on the
patches themselves (torch, the ``train`` extra).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

#: The 30 statistics of a patch the feature judges see, in :func:`patch_features`' order.
PATCH_FEATURES: tuple[str, ...] = (
    "mean", "std", "cv", "skewness", "kurtosis",
    "q01", "q05", "q10", "q25", "q50", "q75", "q90", "q95", "q99",
    "acf_x1", "acf_y1", "acf_x2", "acf_y2", "acf_diag1",
    "band1", "band2", "band3", "band4",
    "gradient", "block8_cv", "row_mean_cv", "col_mean_cv",
    "saturated", "dark", "entropy",
)


def patch_features(patch: NDArray) -> NDArray[np.float64]:
    """(30,) :data:`PATCH_FEATURES` of one (P, P) patch (grey levels 0..255): level, spread and
    shape of the grey histogram, quantiles over the patch mean, autocorrelation at lags 1-2
    along x, y and the diagonal, spectral energy in four radial bands (0-1/16, 1/16-1/8,
    1/8-1/4, 1/4-1/2 cycle/px), mean gradient, spread of 8 x 8 block, row and column means, share
    of saturated (>= 250) and dark (< mean / 4) pixels, histogram entropy (32 bins, bits)."""
    p = patch.astype(np.float64)
    m = p.mean()
    d = p - m
    s = d.std()
    mu = max(m, 1e-6)
    sd = max(s, 1e-9)
    q = np.percentile(p, [1, 5, 10, 25, 50, 75, 90, 95, 99]) / mu

    def acf(dy: int, dx: int) -> float:
        a = d[:d.shape[0] - dy, :d.shape[1] - dx]
        b = d[dy:, dx:]
        return float((a * b).mean() / sd ** 2)

    spec = np.abs(np.fft.fft2(d)) ** 2
    f = np.fft.fftfreq(p.shape[0])
    rad = np.hypot(f[:, None], f[None, :])
    tot = max(spec.sum(), 1e-12)
    edges = (0.0, 1 / 16, 1 / 8, 1 / 4, 0.75)
    bands = [spec[(rad > lo) & (rad <= hi)].sum() / tot for lo, hi in zip(edges[:-1], edges[1:])]
    gy, gx = np.gradient(p)
    n8 = p.shape[0] // 8
    blocks = p[:n8 * 8, :n8 * 8].reshape(n8, 8, n8, 8).mean(axis=(1, 3))
    hist = np.bincount(np.clip(p // 8, 0, 31).astype(int).ravel(), minlength=32) / p.size
    ent = -float(np.sum(hist[hist > 0] * np.log2(hist[hist > 0])))
    return np.array([
        m, s, s / mu, float((d ** 3).mean() / sd ** 3), float((d ** 4).mean() / sd ** 4),
        *q, acf(0, 1), acf(1, 0), acf(0, 2), acf(2, 0), acf(1, 1), *bands,
        float(np.hypot(gx, gy).mean() / mu), float(blocks.std() / mu), float(p.mean(axis=1).std() / mu),
        float(p.mean(axis=0).std() / mu), float(np.mean(p >= 250)), float(np.mean(p < 0.25 * m)), ent])


@dataclass(frozen=True)
class TwoSampleResult:
    """Held-out accuracy of one judge: its name, the accuracy, patches scored and the exact
    95 % interval of the accuracy."""

    judge: str
    accuracy: float
    n_scored: int
    ci95: tuple[float, float]


def balanced_sets(real: NDArray, real_groups: NDArray, sim: NDArray, sim_groups: NDArray,
                  rng: np.random.Generator) -> tuple[NDArray, NDArray, NDArray]:
    """Subsample the larger set to the smaller's size: ``(X, y, groups)`` with y = 1 for real;
    group ids of the simulated set are offset past the real ones."""
    n = min(len(real), len(sim))
    ir = np.sort(rng.choice(len(real), n, replace=False))
    js = np.sort(rng.choice(len(sim), n, replace=False))
    X = np.concatenate([real[ir], sim[js]])
    y = np.concatenate([np.ones(n, dtype=int), np.zeros(n, dtype=int)])
    g = np.concatenate([real_groups[ir], sim_groups[js] + int(real_groups.max()) + 1])
    return X, y, g


def feature_judges(X: NDArray, y: NDArray, groups: NDArray, *, folds: int = 5, seed: int = 0
                   ) -> list[TwoSampleResult]:
    """Held-out accuracies of logistic regression (standardised features) and gradient
    boosting on features ``X`` (n, 30) labelled ``y``; folds grouped by ``groups`` (frames).

    Raises:
        ImportError: scikit-learn is not installed (``pip install 'auvsim[realism]'``).
    """
    from sklearn.ensemble import HistGradientBoostingClassifier
    from sklearn.linear_model import LogisticRegression
    from sklearn.model_selection import GroupKFold, cross_val_predict
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    X = np.nan_to_num(np.asarray(X, dtype=float))
    cv = GroupKFold(n_splits=min(folds, len(np.unique(groups))))
    judges = {
        "logistic regression": make_pipeline(StandardScaler(), LogisticRegression(max_iter=2000, C=1.0)),
        "gradient boosting": HistGradientBoostingClassifier(max_iter=200, learning_rate=0.1, random_state=seed),
    }
    out = []
    for name, clf in judges.items():
        pred = cross_val_predict(clf, X, y, groups=groups, cv=cv)
        out.append(_result(name, pred == y))
    return out


def cnn_judge(patches: NDArray, y: NDArray, groups: NDArray, *, seed: int = 0, epochs: int = 8,
              size_px: int = 32) -> TwoSampleResult:
    """Held-out accuracy of a small CNN (three 3 x 3 conv layers, 8-16-32 channels, global
    pooling) on the patches (n, P, P) downsampled to ``size_px``, two folds grouped by frame.
    Each patch is scaled by 1/255 (its level is visible to the judge, as to the feature judges).

    Raises:
        ImportError: torch is not installed (``pip install 'auvsim[train]'``).
    """
    import cv2
    import torch
    from torch import nn

    torch.manual_seed(seed)
    x = np.stack([cv2.resize(p.astype(np.float32), (size_px, size_px), interpolation=cv2.INTER_AREA)
                  for p in patches]) / 255.0
    ug = np.unique(groups)
    rng = np.random.default_rng(seed)
    fold_of = dict(zip(ug, rng.permutation(len(ug)) % 2))
    fold = np.array([fold_of[g] for g in groups])
    correct = np.zeros(len(y), dtype=bool)
    for k in (0, 1):
        tr, te = fold != k, fold == k
        net = nn.Sequential(
            nn.Conv2d(1, 8, 3, padding=1), nn.ReLU(), nn.MaxPool2d(2),
            nn.Conv2d(8, 16, 3, padding=1), nn.ReLU(), nn.MaxPool2d(2),
            nn.Conv2d(16, 32, 3, padding=1), nn.ReLU(), nn.AdaptiveAvgPool2d(1), nn.Flatten(), nn.Linear(32, 1))
        opt = torch.optim.Adam(net.parameters(), lr=3e-3)
        xt = torch.from_numpy(x[tr, None].astype(np.float32))
        yt = torch.from_numpy(y[tr].astype(np.float32))
        for _ in range(epochs):
            perm = torch.randperm(len(xt))
            for i in range(0, len(xt), 64):
                b = perm[i:i + 64]
                opt.zero_grad()
                loss = nn.functional.binary_cross_entropy_with_logits(net(xt[b]).squeeze(1), yt[b])
                loss.backward()
                opt.step()
        with torch.no_grad():
            logit = net(torch.from_numpy(x[te, None].astype(np.float32))).squeeze(1).numpy()
        correct[te] = (logit > 0).astype(int) == y[te]
    return _result("small CNN", correct)


def _result(name: str, correct: NDArray[np.bool_]) -> TwoSampleResult:
    from sim.evaluation.binomial_interval import proportion_ci95

    k, n = int(correct.sum()), int(correct.size)
    return TwoSampleResult(name, k / n if n else float("nan"), n, proportion_ci95(k, n))
