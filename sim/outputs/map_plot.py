"""``map.png``: survey path, waypoints, true objects and world-model estimates (NED plan view).

East is the horizontal axis and north the vertical one, both in metres at equal scale. The
figure is sized to the survey's aspect (within bounds, so a 160 x 40 m survey gives a wide
figure, not a thin strip) and the legend sits outside the axes. Each kind of item has its
own marker; world-model not-target estimates are drawn above everything else, as a cross
with a white edge, so one stays visible on top of a true target's star.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class MarkerStyle:
    """Look of one kind of map item (matplotlib marker code, colour, size in points, zorder)."""

    label: str
    marker: str
    color: str
    size_pt: float
    zorder: float


# One entry per kind; the markers are all different (tests check it).
STYLES: dict[str, MarkerStyle] = {
    "waypoints": MarkerStyle("waypoints", "s", "0.55", 4.0, 2.0),
    "start": MarkerStyle("start", "o", "tab:blue", 6.0, 3.0),
    "true_target": MarkerStyle("true targets", "*", "tab:green", 13.0, 4.0),
    "true_other": MarkerStyle("true non-target objects", "^", "tab:brown", 8.0, 4.0),
    "wm_target": MarkerStyle("world model: target (2-sigma)", "+", "tab:red", 11.0, 5.0),
    "wm_not_target": MarkerStyle("world model: not target", "X", "tab:purple", 8.0, 6.0),
}

# Bounds on the size of the data area (inches) and the extra room around it; beyond the bounds the
# axes box keeps the data aspect and leaves blank space.
AXES_AREA_IN2 = 40.0
AXES_WIDTH_IN = (4.0, 13.0)
AXES_HEIGHT_IN = (2.5, 9.0)
MIN_EXTENT_M = 10.0
MARGIN_FRACTION = 0.06
WIDE_ASPECT = 1.6  # wider than this: legend below the map, else to its right
DPI = 110


def _ellipse_ne(mean_ne: NDArray, cov_ne: NDArray, n_sigma: float = 2.0, n_pts: int = 60) -> NDArray:
    """(n_pts, 2) north/east points of the n-sigma ellipse of a 2-D Gaussian."""
    vals, vecs = np.linalg.eigh(0.5 * (cov_ne + cov_ne.T))
    vals = np.clip(vals, 0.0, None)
    t = np.linspace(0.0, 2.0 * np.pi, n_pts)
    circle = np.stack([np.cos(t), np.sin(t)])
    return (mean_ne[:, None] + vecs @ (n_sigma * np.sqrt(vals)[:, None] * circle)).T


def map_extent_ne(points_ne: NDArray) -> tuple[tuple[float, float], tuple[float, float]]:
    """((n_min, n_max), (e_min, e_max)) in metres: the points' bounding box with a margin,
    each side at least ``MIN_EXTENT_M`` long.

    Args:
        points_ne: (k, 2) north/east positions (m); k >= 1.

    Raises:
        ValueError: no points, or not of shape (k, 2).
    """
    pts = np.asarray(points_ne, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) == 0:
        raise ValueError(f"points_ne must be (k, 2) with k >= 1, got {pts.shape}")
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if len(pts) == 0:
        raise ValueError("points_ne has no finite point")
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = np.maximum(hi - lo, MIN_EXTENT_M)
    centre = 0.5 * (lo + hi)
    half = 0.5 * span * (1.0 + 2.0 * MARGIN_FRACTION)
    return (centre[0] - half[0], centre[0] + half[0]), (centre[1] - half[1], centre[1] + half[1])


def axes_size_in(width_m: float, height_m: float) -> tuple[float, float]:
    """(width, height) in inches of the data area for a map ``width_m`` east by ``height_m``
    north: the same aspect at about ``AXES_AREA_IN2`` square inches, clipped to
    ``AXES_WIDTH_IN`` and ``AXES_HEIGHT_IN`` (an extreme aspect then leaves blank space).

    Raises:
        ValueError: a non-positive extent.
    """
    if not (width_m > 0.0 and height_m > 0.0):
        raise ValueError(f"map extents must be positive, got {width_m} x {height_m} m")
    aspect = width_m / height_m
    w = float(np.clip(np.sqrt(AXES_AREA_IN2 * aspect), *AXES_WIDTH_IN))
    h = float(np.clip(w / aspect, *AXES_HEIGHT_IN))
    w = float(np.clip(h * aspect, *AXES_WIDTH_IN))
    return w, h


def build_map_figure(
    *,
    true_pos_ned: NDArray,
    est_pos_ned: NDArray | None,
    waypoints_ne: NDArray | None,
    targets: Sequence[tuple[str, NDArray, bool]],
    estimates: Sequence[tuple[str, NDArray, NDArray]] = (),
    rejected_ned: Sequence[NDArray] = (),
    title: str = "",
    overlay=None,
    extent_points_ne: NDArray | None = None,
    other_paths: Sequence[tuple[str, NDArray]] = (),
    surface_estimates_ned: Sequence[NDArray] = (),
):
    """Plan-view map as a matplotlib ``Figure`` on an Agg canvas (no pyplot state to close).

    Args:
        true_pos_ned: (n, 3) true path, NED metres (n >= 0).
        est_pos_ned: (n, 3) navigation estimate, NED metres, or None.
        waypoints_ne: (k, 2) planned waypoints, north/east metres, or None.
        targets: (name, pos_ned (3,), is_target) for every scene object (true positions).
        estimates: (label, pos_ned (3,), cov_ned (3, 3) m^2) world-model targets, drawn with
            their 2-sigma horizontal ellipse.
        rejected_ned: (3,) NED positions of world-model objects classified as not-targets.
        title: figure title.
        overlay: optional ``draw(ax)`` adding artists (x east, y north, metres; labelled
            artists join the legend; their points do not change the extent).
        extent_points_ne: (m, 2) more north/east points the map must show (an overlay's).
        other_paths: (name, (n, 3) NED path) of each extra vehicle (the surface buoy's track).
        surface_estimates_ned: (3,) NED positions of the surface world model's targets.

    Returns:
        matplotlib.figure.Figure, its size set from the map's aspect (``axes_size_in``) plus
        room for labels and the legend (below the map when it is wider than
        ``WIDE_ASPECT``, to its right otherwise).

    Raises:
        ValueError: nothing to plot (no path, waypoint, object or estimate).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    true_pos_ned = np.asarray(true_pos_ned, dtype=float).reshape(-1, 3)
    pts = [true_pos_ned[:, :2]]
    if est_pos_ned is not None:
        pts.append(np.asarray(est_pos_ned, dtype=float).reshape(-1, 3)[:, :2])
    if waypoints_ne is not None:
        pts.append(np.asarray(waypoints_ne, dtype=float).reshape(-1, 2))
    pts += [np.asarray(p, dtype=float)[None, :2] for _, p, _ in targets]
    pts += [np.asarray(p, dtype=float)[None, :2] for _, p, _ in estimates]
    pts += [np.asarray(p, dtype=float)[None, :2] for p in rejected_ned]
    if extent_points_ne is not None:
        pts.append(np.asarray(extent_points_ne, dtype=float).reshape(-1, 2))
    pts += [np.asarray(p, dtype=float).reshape(-1, 3)[:, :2] for _, p in other_paths]
    pts += [np.asarray(p, dtype=float)[None, :2] for p in surface_estimates_ned]
    (n0, n1), (e0, e1) = map_extent_ne(np.concatenate(pts, axis=0))

    ax_w, ax_h = axes_size_in(e1 - e0, n1 - n0)
    wide = (e1 - e0) / (n1 - n0) > WIDE_ASPECT
    fig_w = ax_w + 1.1 + (0.0 if wide else 2.6)
    fig_h = ax_h + 0.8 + (0.3 if title else 0.0) + (0.55 if wide else 0.0)
    fig = Figure(figsize=(fig_w, fig_h), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()

    def style(kind: str, **kw) -> dict:
        s = STYLES[kind]
        return dict(marker=s.marker, color=s.color, ms=s.size_pt, zorder=s.zorder, **kw)

    if waypoints_ne is not None and len(waypoints_ne):
        ax.plot(waypoints_ne[:, 1], waypoints_ne[:, 0], ls="--", lw=0.8,
                label=STYLES["waypoints"].label, **style("waypoints"))
    ax.plot(true_pos_ned[:, 1], true_pos_ned[:, 0], "-", color="tab:blue", lw=1.4, zorder=2.5,
            label="true path")
    if est_pos_ned is not None and len(est_pos_ned):
        ax.plot(est_pos_ned[:, 1], est_pos_ned[:, 0], "-", color="tab:orange", lw=1.0, alpha=0.9,
                zorder=2.6, label="estimated path")
    for name, path in other_paths:
        path = np.asarray(path, dtype=float).reshape(-1, 3)
        ax.plot(path[:, 1], path[:, 0], "-", color="tab:green", lw=0.9, alpha=0.8, zorder=2.4,
                label=f"{name} track (true)")
    if len(surface_estimates_ned):
        ne = np.array([np.asarray(p, dtype=float)[:2] for p in surface_estimates_ned])
        ax.plot(ne[:, 1], ne[:, 0], ls="none", marker="+", color="tab:green", ms=9, mew=1.4, zorder=6.5,
                label="surface world model target")
    if len(true_pos_ned):
        ax.plot(true_pos_ned[:1, 1], true_pos_ned[:1, 0], ls="none", label=STYLES["start"].label,
                **style("start"))
    for kind, want in (("true_target", True), ("true_other", False)):
        objs = [(name, np.asarray(pos, dtype=float)) for name, pos, is_t in targets if bool(is_t) == want]
        if not objs:
            continue
        ne = np.array([p[:2] for _, p in objs])
        ax.plot(ne[:, 1], ne[:, 0], ls="none", label=STYLES[kind].label, mec="white", mew=0.6,
                **style(kind))
        for name, pos in objs:
            ax.annotate(name, (pos[1], pos[0]), textcoords="offset points", xytext=(6, 5), fontsize=7,
                        color=STYLES[kind].color, zorder=7)
    if len(estimates):
        for _, pos, cov in estimates:
            ell = _ellipse_ne(np.asarray(pos, dtype=float)[:2], np.asarray(cov, dtype=float)[:2, :2])
            ax.plot(ell[:, 1], ell[:, 0], "-", color=STYLES["wm_target"].color, lw=0.9,
                    zorder=STYLES["wm_target"].zorder)
        ne = np.array([np.asarray(p, dtype=float)[:2] for _, p, _ in estimates])
        ax.plot(ne[:, 1], ne[:, 0], ls="none", mew=1.6, label=STYLES["wm_target"].label,
                **style("wm_target"))
        for label, pos, _ in estimates:
            ax.annotate(label, (pos[1], pos[0]), textcoords="offset points", xytext=(-10, -11),
                        fontsize=7, color=STYLES["wm_target"].color, zorder=7)
    if len(rejected_ned):
        ne = np.array([np.asarray(p, dtype=float)[:2] for p in rejected_ned])
        ax.plot(ne[:, 1], ne[:, 0], ls="none", mec="white", mew=0.7,
                label=STYLES["wm_not_target"].label, **style("wm_not_target"))

    if overlay is not None:
        overlay(ax)
    ax.set_xlim(e0, e1)
    ax.set_ylim(n0, n1)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("East (m)")
    ax.set_ylabel("North (m)")
    ax.grid(True, alpha=0.3)
    if title:
        ax.set_title(title)
    n_items = len(ax.get_legend_handles_labels()[0])
    if wide:
        fig.legend(loc="outside lower center", ncols=min(n_items, 4), fontsize=8, frameon=False)
    else:
        fig.legend(loc="outside right upper", ncols=1, fontsize=8, frameon=False)
    return fig


def plot_map(path: Path, **kwargs) -> None:
    """Write the plan-view map of :func:`build_map_figure` (same keyword arguments) to ``path``
    (PNG, ``DPI`` dots per inch).

    Raises:
        ValueError: see :func:`build_map_figure`.
    """
    fig = build_map_figure(**kwargs)
    fig.savefig(path)
