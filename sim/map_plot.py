"""``map.png``: survey path, waypoints, true targets and world-model estimates (NED plan view)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray


def _ellipse_ne(mean_ne: NDArray, cov_ne: NDArray, n_sigma: float = 2.0, n_pts: int = 60) -> NDArray:
    vals, vecs = np.linalg.eigh(0.5 * (cov_ne + cov_ne.T))
    vals = np.clip(vals, 0.0, None)
    t = np.linspace(0.0, 2.0 * np.pi, n_pts)
    circle = np.stack([np.cos(t), np.sin(t)])
    return (mean_ne[:, None] + vecs @ (n_sigma * np.sqrt(vals)[:, None] * circle)).T


def plot_map(
    path: Path,
    *,
    true_pos_ned: NDArray,
    est_pos_ned: NDArray | None,
    waypoints_ne: NDArray | None,
    targets: Sequence[tuple[str, NDArray, bool]],
    estimates: Sequence[tuple[str, NDArray, NDArray]] = (),
    rejected_ned: Sequence[NDArray] = (),
    title: str = "",
) -> None:
    """Write a plan-view map. East is the horizontal axis, north the vertical.

    Args:
        true_pos_ned: (n, 3) true path.
        est_pos_ned: (n, 3) navigation estimate, or None.
        waypoints_ne: (k, 2) planned waypoints, or None.
        targets: (name, pos_ned (3,), is_target) for every scene object.
        estimates: (label, pos_ned (3,), cov_ned (3, 3)) world-model targets.
        rejected_ned: positions of world-model objects classified as not-targets.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 7), dpi=110)
    if waypoints_ne is not None and len(waypoints_ne):
        ax.plot(waypoints_ne[:, 1], waypoints_ne[:, 0], "s--", color="0.6", ms=4, lw=0.8, label="waypoints")
    ax.plot(true_pos_ned[:, 1], true_pos_ned[:, 0], "-", color="tab:blue", lw=1.4, label="true path")
    if est_pos_ned is not None:
        ax.plot(est_pos_ned[:, 1], est_pos_ned[:, 0], "-", color="tab:orange", lw=1.0, alpha=0.9, label="estimated path")
    if len(true_pos_ned):
        ax.plot(true_pos_ned[0, 1], true_pos_ned[0, 0], "o", color="tab:blue", ms=6)
    for i, (name, pos, is_target) in enumerate(targets):
        ax.plot(pos[1], pos[0], "*" if is_target else "x", color="tab:green" if is_target else "0.4", ms=12,
                label=("true targets" if is_target else "distractors") if i == 0 else None)
        ax.annotate(name, (pos[1], pos[0]), textcoords="offset points", xytext=(6, 6), fontsize=8, color="tab:green")
    for i, (label, pos, cov) in enumerate(estimates):
        ell = _ellipse_ne(np.asarray(pos[:2]), np.asarray(cov)[:2, :2])
        ax.plot(ell[:, 1], ell[:, 0], "-", color="tab:red", lw=0.9)
        ax.plot(pos[1], pos[0], "+", color="tab:red", ms=10, mew=1.6, label="world model (2-sigma)" if i == 0 else None)
        ax.annotate(label, (pos[1], pos[0]), textcoords="offset points", xytext=(-14, -12), fontsize=7, color="tab:red")
    for i, pos in enumerate(rejected_ned):
        ax.plot(pos[1], pos[0], "x", color="0.5", ms=7, label="world model: not target" if i == 0 else None)
    ax.set_xlabel("East (m)")
    ax.set_ylabel("North (m)")
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    if title:
        ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
