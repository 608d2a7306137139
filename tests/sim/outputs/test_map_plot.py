"""map.png: figure sized to the survey's aspect, legend off the data, one marker per kind."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.colors import to_rgb

from sim.outputs.map_plot import AXES_HEIGHT_IN, AXES_WIDTH_IN, STYLES, axes_size_in, build_map_figure, plot_map


def lawnmower(width_e_m: float, height_n_m: float, spacing_m: float = 8.0) -> tuple[np.ndarray, np.ndarray]:
    """Waypoints (k, 2) N/E and a densely sampled path (n, 3) NED over the rectangle."""
    wps = []
    for i, n in enumerate(np.arange(0.0, height_n_m + 1e-9, spacing_m)):
        e = (0.0, width_e_m) if i % 2 == 0 else (width_e_m, 0.0)
        wps += [(n, e[0]), (n, e[1])]
    wps = np.array(wps)
    path = np.concatenate([np.linspace(a, b, 50) for a, b in zip(wps[:-1], wps[1:])])
    return wps, np.column_stack([path, np.full(len(path), 5.0)])


def survey_figure(width_e_m: float, height_n_m: float, **kw):
    wps, path = lawnmower(width_e_m, height_n_m)
    star = np.array([0.3 * height_n_m, 0.4 * width_e_m, 10.0])
    targets = [("OPI1", star, True), ("OPI2", np.array([0.7 * height_n_m, 0.8 * width_e_m, 10.0]), True),
               ("rock1", np.array([0.5 * height_n_m, 0.2 * width_e_m, 10.0]), False)]
    estimates = [("0", targets[1][1] + [0.3, -0.2, 0.0], np.diag([0.4, 0.3, 0.1]))]
    rejected = [star.copy(), targets[2][1] + [0.2, 0.1, 0.0]]  # a not-target right on a star
    fig = build_map_figure(true_pos_ned=path, est_pos_ned=path + [0.2, -0.1, 0.0], waypoints_ne=wps,
                           targets=targets, estimates=estimates, rejected_ned=rejected, title="t", **kw)
    fig.draw_without_rendering()
    return fig, star


def data_box_aspect(fig) -> tuple[float, float]:
    """(display width / height of the axes box, data width / height of its limits)."""
    ax = fig.axes[0]
    bb = ax.get_window_extent()
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    return bb.width / bb.height, (x1 - x0) / (y1 - y0)


@pytest.mark.parametrize("width_m, height_m", [(160.0, 40.0), (40.0, 40.0), (30.0, 90.0)])
def test_figure_follows_the_survey_aspect(width_m, height_m):
    fig, _ = survey_figure(width_m, height_m)
    box, data = data_box_aspect(fig)
    assert box == pytest.approx(data, rel=0.02)  # equal scale in east and north
    assert data == pytest.approx(width_m / height_m, rel=0.15)  # limits hug the survey
    w_in, h_in = fig.get_size_inches()
    bb = fig.axes[0].get_window_extent()
    ax_w_in, ax_h_in = bb.width / fig.dpi, bb.height / fig.dpi
    # The data area uses most of the figure along the survey's long side, and is not tiny.
    assert ax_w_in * ax_h_in > 15.0
    if width_m > 2 * height_m:
        assert w_in / h_in > 2.0 and ax_w_in / w_in > 0.85
    if width_m == height_m:
        assert 0.9 < ax_w_in / ax_h_in < 1.1
    # Within the bounds, give or take what the layout engine hands back from the margins.
    # (A short side may fall below its minimum: the box keeps the data aspect.)
    assert ax_w_in <= 1.1 * AXES_WIDTH_IN[1] and ax_h_in <= 1.1 * AXES_HEIGHT_IN[1]
    assert ax_w_in >= 0.9 * AXES_WIDTH_IN[0] or ax_h_in >= 0.9 * AXES_HEIGHT_IN[1]
    assert ax_h_in >= 0.9 * AXES_HEIGHT_IN[0] or ax_w_in >= 0.9 * AXES_WIDTH_IN[1]


def test_axes_size_is_bounded_for_extreme_aspects():
    for w_m, h_m in [(400.0, 10.0), (10.0, 400.0), (1e4, 1e4), (1.0, 1.0)]:
        w, h = axes_size_in(w_m, h_m)
        assert AXES_WIDTH_IN[0] <= w <= AXES_WIDTH_IN[1] and AXES_HEIGHT_IN[0] <= h <= AXES_HEIGHT_IN[1]
    w, h = axes_size_in(160.0, 40.0)
    assert w / h == pytest.approx(4.0, rel=1e-9)
    with pytest.raises(ValueError):
        axes_size_in(0.0, 10.0)


@pytest.mark.parametrize("width_m, height_m", [(160.0, 40.0), (40.0, 40.0)])
def test_legend_is_outside_the_data_area(width_m, height_m):
    fig, _ = survey_figure(width_m, height_m)
    assert len(fig.legends) == 1 and fig.axes[0].get_legend() is None
    leg = fig.legends[0].get_window_extent()
    ax = fig.axes[0].get_window_extent()
    assert not leg.overlaps(ax)
    fig_bb = fig.bbox
    assert leg.x0 >= fig_bb.x0 and leg.x1 <= fig_bb.x1 and leg.y0 >= fig_bb.y0 and leg.y1 <= fig_bb.y1


def two_vehicle_figure():
    """The survey with a surface vehicle's track and its world model's targets (the sea trial)."""
    _, path = lawnmower(160.0, 40.0)
    return survey_figure(160.0, 40.0, other_paths=[("buoy", path + [4.0, 0.0, -10.0])],
                         surface_estimates_ned=[np.array([12.0, 64.0, 10.0])])


def test_each_kind_has_its_own_marker():
    fig, _ = two_vehicle_figure()
    by_label = {}
    for line in fig.axes[0].get_lines():
        label = line.get_label()
        if not label.startswith("_") and line.get_marker() not in ("None", None, ""):
            by_label[label] = (line.get_marker(), to_rgb(line.get_color()))
    kinds = {s.label for s in STYLES.values()}
    assert kinds <= set(by_label)
    markers = [by_label[k][0] for k in kinds]
    assert len(set(markers)) == len(kinds)
    # Real non-target objects and world-model not-targets differ in marker and colour.
    rock, rejected = by_label["true non-target objects"], by_label["world model: not target"]
    assert rock[0] != rejected[0] and rock[1] != rejected[1]
    assert {"true path", "estimated path"} <= {ln.get_label() for ln in fig.axes[0].get_lines()}


def test_not_target_estimate_stays_visible_on_a_target_star():
    """Rendered pixels: at a not-target placed exactly on a target star, the not-target's
    colour shows (it is drawn above the star)."""
    fig, star = survey_figure(160.0, 40.0)
    ax = fig.axes[0]
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    assert lines["world model: not target"].get_zorder() > lines["true targets"].get_zorder()
    fig.canvas.draw()
    img = np.asarray(fig.canvas.buffer_rgba())[..., :3] / 255.0
    x, y = ax.transData.transform((star[1], star[0]))
    row, col = int(round(img.shape[0] - y)), int(round(x))
    patch = img[row - 1:row + 2, col - 1:col + 2].reshape(-1, 3)
    purple, green = np.array(to_rgb(STYLES["wm_not_target"].color)), np.array(to_rgb(STYLES["true_target"].color))
    assert np.min(np.linalg.norm(patch - purple, axis=1)) < 0.05
    assert np.min(np.linalg.norm(patch - green, axis=1)) > 0.2


def test_plot_map_writes_a_png_of_the_figure_size(tmp_path):
    from PIL import Image

    wps, path = lawnmower(160.0, 40.0)
    out = tmp_path / "map.png"
    plot_map(out, true_pos_ned=path, est_pos_ned=None, waypoints_ne=wps, targets=[], title="wide")
    w_px, h_px = Image.open(out).size
    fig = build_map_figure(true_pos_ned=path, est_pos_ned=None, waypoints_ne=wps, targets=[], title="wide")
    assert (w_px, h_px) == tuple(int(round(v)) for v in fig.get_size_inches() * fig.dpi)
    assert w_px / h_px > 2.0
    with pytest.raises(ValueError):
        build_map_figure(true_pos_ned=np.zeros((0, 3)), est_pos_ned=None, waypoints_ne=None, targets=[])


def test_surface_vehicle_track_and_model_have_their_own_colour():
    """The buoy's track and its world model's targets do not take the colours of the AUV's
    paths, the true targets or the AUV's world model (the sea trial's map)."""
    fig, _ = two_vehicle_figure()
    colours = {ln.get_label(): np.array(to_rgb(ln.get_color())) for ln in fig.axes[0].get_lines()}
    for mine in ("buoy track (true)", STYLES["surface_wm_target"].label):
        for other in ("true path", "estimated path", "true targets", STYLES["wm_target"].label,
                      STYLES["wm_not_target"].label, "true non-target objects"):
            assert np.linalg.norm(colours[mine] - colours[other]) > 0.2, (mine, other)
