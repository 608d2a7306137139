"""map.png of a tracking mission: the movers' true paths (not their start points, not the
parked bubble scatterers) and the tracker's estimate; no survey waypoints for a buddy
mission, which does not fly them."""

from __future__ import annotations

import numpy as np

from scenarios.load import load_scenario
from sim.features import TrackingFeature
from sim.mission import Mission
from sim.outputs.map_plot import build_map_figure
from sim.mission.run import map_layers, planned_length_s
from sim.outputs.tracking_overlay import mover_paths_ned


def _short_mission(name: str, *overrides: str):
    mission = Mission(load_scenario(name, ["duration_s=3", *overrides]))
    ev = mission.feature(TrackingFeature).observers({})[0]
    mission.observers.append(ev)
    mission.reset()
    mission.run(progress=False)
    return mission, ev


def test_buddy_mission_map_layers():
    mission, ev = _short_mission("track_static_vehicle")
    layers = map_layers(mission, 3.0)
    assert layers["waypoints_ne"] is None  # hover: the default survey plan is not flown
    assert layers["targets"] == []  # the diver is a path, its bubbles are not drawn at their parking spot
    traj = mission.physics.movers.trajectories["diver"]
    paths = mover_paths_ned(mission.physics.movers, 3.0)
    assert np.allclose(paths["diver"][0], traj.pose_at(0.0)[0]) and np.allclose(paths["diver"][-1], traj.pose_at(3.0)[0])
    # the map must show where the diver went and the estimate
    ext = layers["extent_points_ne"]
    assert np.allclose(ext[: len(paths["diver"])], paths["diver"][:, :2])
    assert len(ev.primary_est_ned) > 0
    fig = build_map_figure(true_pos_ned=np.zeros((2, 3)), est_pos_ned=None, estimates=(), **layers)
    labels = fig.axes[0].get_legend_handles_labels()[1]
    assert "waypoints" not in labels and "true non-target objects" not in labels
    assert "true mover path (o start, * end)" in labels and "tracker estimate (fused)" in labels
    assert planned_length_s(mission) == 3.0


def test_survey_with_tracking_keeps_its_waypoints():
    mission, ev = _short_mission("track_moving_vehicle")
    layers = map_layers(mission, 3.0)
    assert layers["waypoints_ne"] is not None and len(layers["waypoints_ne"]) > 2
