"""Map overlay of a target-tracking mission: each mover's true path (start and end marked)
and the primary tracker's estimate of the tracked one, so ``map.png`` shows who moved where
rather than the movers' start points alone."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

#: Time step of the sampled true mover paths, s.
PATH_STEP_S = 0.5


def mover_paths_ned(movers, duration_s: float, step_s: float = PATH_STEP_S) -> dict[str, NDArray[np.float64]]:
    """name -> (n, 3) true NED path of each mover over ``[0, duration_s]``, m.

    Args:
        movers: :class:`sim.scene.movers.MovingBodies` (its ``trajectories``).
        duration_s: how long the run lasted, s.
        step_s: sample spacing, s.
    """
    t = np.append(np.arange(0.0, duration_s, step_s), duration_s)
    return {name: np.array([traj.pose_at(float(ti))[0] for ti in t]) for name, traj in movers.trajectories.items()}


def extent_points_ne(paths: dict[str, NDArray], est_ned: NDArray | None) -> NDArray[np.float64]:
    """(k, 2) north/east points the map must show: the paths and the estimate."""
    pts = [np.asarray(p, dtype=float)[:, :2] for p in paths.values()]
    if est_ned is not None and len(est_ned):
        pts.append(np.asarray(est_ned, dtype=float)[:, :2])
    return np.concatenate(pts, axis=0) if pts else np.zeros((0, 2))


def tracking_overlay(paths: dict[str, NDArray], est_ned: NDArray | None, est_label: str):
    """A function ``draw(ax)`` for :func:`sim.outputs.map_plot.build_map_figure`'s ``overlay``
    (x east, y north, m): true mover paths (green, a star at the end, a ring at the start) and
    the tracker's estimate ``est_ned`` ((m, 3) NED, m; dashed)."""

    def draw(ax) -> None:
        for i, (name, p) in enumerate(paths.items()):
            ax.plot(p[:, 1], p[:, 0], "-", color="tab:green", lw=1.3, zorder=3,
                    label="true mover path (o start, * end)" if i == 0 else None)
            ax.plot(p[0, 1], p[0, 0], "o", mfc="none", color="tab:green", ms=7, zorder=3)
            ax.plot(p[-1, 1], p[-1, 0], "*", color="tab:green", ms=13, mec="white", mew=0.6, zorder=4)
            ax.annotate(name, (p[-1, 1], p[-1, 0]), textcoords="offset points", xytext=(6, 5), fontsize=7,
                        color="tab:green", zorder=7)
        if est_ned is not None and len(est_ned):
            e = np.asarray(est_ned, dtype=float)
            ax.plot(e[:, 1], e[:, 0], "--", color="tab:red", lw=0.9, zorder=3.5, label=est_label)

    return draw
