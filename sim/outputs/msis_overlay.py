"""Map overlay of a scanning-sonar mission: the true pool / tank outline, the last fitted
circle or fuzzy segments (with their 95 % rho bands, in the navigation frame of their fix),
the dead-reckoned path of the same run and the sonar position fixes."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # drawn from its recorded path and fixes
    from sim.evaluation.msis_localization import LocalizationErrorObserver


def basin_outline_ne(basin) -> np.ndarray | None:
    """(m, 2) north/east points of the basin's inner outline (None without walls)."""
    if basin.shape == "circular":
        a = np.linspace(0.0, 2 * np.pi, 200)
        return np.column_stack([basin.center_ne_m[0] + basin.radius_m * np.cos(a),
                                basin.center_ne_m[1] + basin.radius_m * np.sin(a)])
    if basin.shape == "rectangular":
        (cn, ce), (ln, le) = basin.center_ne_m, basin.size_ne_m
        return np.column_stack([cn + 0.5 * ln * np.array([-1, 1, 1, -1, -1]),
                                ce + 0.5 * le * np.array([-1, -1, 1, 1, -1])])
    return None


def msis_overlay(obs: LocalizationErrorObserver, basin, localizer):
    """A function ``draw(ax)`` for :func:`sim.outputs.map_plot.build_map_figure`'s ``overlay``
    (axes: x east, y north, metres)."""

    def draw(ax) -> None:
        outline = basin_outline_ne(basin)
        if outline is not None:
            ax.plot(outline[:, 1], outline[:, 0], "k-", lw=1.2, label=f"true {basin.shape} basin wall")
        if obs.dr_path_ne:
            dr = np.asarray(obs.dr_path_ne)
            ax.plot(dr[:, 1], dr[:, 0], "-", color="tab:gray", lw=0.9, label="dead-reckoned path")
        if obs.fixes:
            f = np.array([m.pos_ne_m for m in obs.fixes])
            ax.plot(f[:, 1], f[:, 0], "x", color="tab:green", ms=4, label="sonar position fixes")
        circle = getattr(localizer, "last_circle", None)
        if circle is not None:
            a = np.linspace(0.0, 2 * np.pi, 200)
            ax.plot(circle.centre[1] + circle.radius_m * np.sin(a), circle.centre[0] + circle.radius_m * np.cos(a),
                    "--", color="tab:red", lw=1.0, label="last fitted circle (nav frame)")
        first = True
        for s in getattr(localizer, "last_segments", []) or []:
            n = s.normal
            for off, style in ((0.0, "-"), (s.rho0_m, ":"), (-s.rho0_m, ":")):
                p = np.array([s.end_a, s.end_b]) + off * n
                ax.plot(p[:, 1], p[:, 0], style, color="tab:red", lw=1.4 if off == 0.0 else 0.7,
                        label="last fuzzy segments, 95 % band" if first else None)
                first = False

    return draw
