"""ROS 2 bag export: read back with rosbags' own reader and checked against the mission's
records, converted to ENU/FLU by independent formulas (scipy Euler angles, axis swaps)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

pytest.importorskip("rosbags")

from rosbags.rosbag2 import Reader  # noqa: E402

from autonomy.messages import Detection, DvlMsg, ImuMsg  # noqa: E402
from scenarios import load_scenario  # noqa: E402
from sim.mission import Mission  # noqa: E402
from sim.events.records import ObserverBase, PerceptionResult  # noqa: E402
from sim.ros2bag.recorder import RosbagRecorder  # noqa: E402
from sim.ros2bag.ros_messages import RosConverter  # noqa: E402
from sim.ros2bag.typestore import make_typestore  # noqa: E402
from sim.sensors.fls import FlsRender  # noqa: E402
from scenarios.fls_presets import resolve_geometry  # noqa: E402
from sim.outputs.trajectory_log import TrajectoryLog  # noqa: E402

DURATION_S = 8.0
# mounts off the body origin (and an altimeter tilted forward) to check the sensor frames
ALT_POS_FRD_M, ALT_PITCH_DEG, DVL_POS_FRD_M = (0.30, -0.10, 0.20), 20.0, (-0.25, 0.05, 0.22)


class _Capture(ObserverBase):
    def __init__(self) -> None:
        self.msgs: dict[str, list] = {}

    def on_start(self, info) -> None: ...

    def on_step(self, r) -> None: ...

    def on_message(self, name, msg) -> None:
        self.msgs.setdefault(type(msg).__name__, []).append(msg)

    def on_end(self, summary) -> None: ...


@pytest.fixture(scope="module")
def bag_run(tmp_path_factory):
    scn = load_scenario("cssn_lawnmower", [
        f"duration_s={DURATION_S}", "autonomy.atr.detector=classical",
        f"sensors.altimeter.mount_pos_body_m={list(ALT_POS_FRD_M)}", f"sensors.altimeter.mount_rpy_deg=[0, {ALT_PITCH_DEG}, 0]",
        f"sensors.dvl.mount_pos_body_m={list(DVL_POS_FRD_M)}"])
    path = tmp_path_factory.mktemp("bag") / "rosbag"
    log, cap = TrajectoryLog(), _Capture()
    mission = Mission(scn, observers=[log, cap, RosbagRecorder(path)])
    mission.reset()
    summary = mission.run(progress=False)
    store = make_typestore()
    topics: dict[str, list] = {}
    meta = yaml.safe_load((path / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["storage_identifier"] == "mcap"
    assert [f["path"] for f in meta["files"]] == ["rosbag.mcap"]
    with Reader(path) as reader:
        msgtypes = {c.topic: c.msgtype for c in reader.connections}
        for conn, t_ns, raw in reader.messages():
            topics.setdefault(conn.topic, []).append((t_ns, store.deserialize_cdr(raw, conn.msgtype)))
    return scn, log, cap, summary, msgtypes, topics


def _stamp_s(h) -> float:
    return h.stamp.sec + 1e-9 * h.stamp.nanosec


def test_topics_and_types(bag_run):
    *_, msgtypes, _ = bag_run
    assert msgtypes == {
        "/tf_static": "tf2_msgs/msg/TFMessage", "/tf": "tf2_msgs/msg/TFMessage",
        "/auvsim/truth/odometry": "nav_msgs/msg/Odometry", "/auvsim/truth/pose": "geometry_msgs/msg/PoseStamped",
        "/auvsim/nav/odometry": "nav_msgs/msg/Odometry", "/auvsim/imu": "sensor_msgs/msg/Imu",
        "/auvsim/dvl": "marine_acoustic_msgs/msg/Dvl", "/auvsim/depth": "sensor_msgs/msg/FluidPressure",
        "/auvsim/altimeter": "sensor_msgs/msg/Range",
        "/auvsim/fls/image": "marine_acoustic_msgs/msg/ProjectedSonarImage",
        "/auvsim/fls/detections": "vision_msgs/msg/Detection2DArray",
        "/auvsim/world_model": "visualization_msgs/msg/MarkerArray",
    }


def test_counts_follow_the_rates(bag_run):
    scn, log, _, summary, _, topics = bag_run
    n_steps = len(log.t_s)
    for topic in ("/tf", "/auvsim/truth/odometry", "/auvsim/truth/pose", "/auvsim/nav/odometry"):
        assert len(topics[topic]) == n_steps
    assert n_steps == round(DURATION_S * scn.autonomy.rate_hz) + 1  # ticks plus the reset record
    for name in ("imu", "dvl", "depth", "altimeter"):
        n = len(topics[f"/auvsim/{name}"])
        assert n == summary.messages_delivered[name]
        assert abs(n - DURATION_S * scn.sensors[name].rate_hz) <= 1
    n_fls = len(topics["/auvsim/fls/image"])
    assert abs(n_fls - DURATION_S * scn.sensors["fls"].rate_hz) <= 1
    assert len(topics["/auvsim/fls/detections"]) == len(topics["/auvsim/world_model"]) == n_fls


def test_stamps_are_sim_time_and_monotonic(bag_run):
    *_, topics = bag_run
    for topic, items in topics.items():
        t_ns = np.array([t for t, _ in items])
        assert np.all(np.diff(t_ns) >= 0), topic
        if topic not in ("/tf", "/tf_static"):
            stamps = np.array([_stamp_s(m.markers[0].header if hasattr(m, "markers") else m.header)
                               for _, m in items])
            np.testing.assert_allclose(stamps, t_ns * 1e-9, atol=1e-9, err_msg=topic)
            assert stamps[-1] <= DURATION_S + 1e-9
            if topic != "/auvsim/world_model":
                assert np.all(np.diff(stamps) > 0), topic


def test_truth_pose_equals_the_trajectory_in_enu(bag_run):
    _, log, _, _, _, topics = bag_run
    poses = [m.pose for _, m in topics["/auvsim/truth/pose"]]
    pos_enu = np.array([[p.position.x, p.position.y, p.position.z] for p in poses])
    ned = log.true_pos_ned
    np.testing.assert_allclose(pos_enu, np.c_[ned[:, 1], ned[:, 0], -ned[:, 2]], rtol=0, atol=1e-9)
    quat = np.array([[p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w] for p in poses])
    roll, pitch, yaw = log.column("true_roll_rad"), log.column("true_pitch_rad"), log.column("true_yaw_rad")
    ref = Rotation.from_euler("ZYX", np.c_[np.pi / 2 - yaw, -pitch, roll])
    np.testing.assert_allclose(Rotation.from_quat(quat).as_matrix(), ref.as_matrix(), atol=1e-9)
    odo = [m.pose.pose.position for _, m in topics["/auvsim/truth/odometry"]]
    np.testing.assert_allclose([[p.x, p.y, p.z] for p in odo], pos_enu, atol=0)
    est = [m.pose.pose.position for _, m in topics["/auvsim/nav/odometry"]]
    e = log.est_pos_ned
    np.testing.assert_allclose([[p.x, p.y, p.z] for p in est], np.c_[e[:, 1], e[:, 0], -e[:, 2]], atol=1e-9)
    cov = np.array([m.pose.covariance.reshape(6, 6) for _, m in topics["/auvsim/nav/odometry"]])
    np.testing.assert_allclose(cov[:, 0, 0], log.column("est_cov_ee_m2"), rtol=1e-6)
    np.testing.assert_allclose(cov[:, 2, 2], log.column("est_cov_dd_m2"), rtol=1e-6)


def test_tf_tree(bag_run):
    *_, topics = bag_run
    static = {(t.header.frame_id, t.child_frame_id) for _, m in topics["/tf_static"] for t in m.transforms}
    assert static == {("map", "odom"), ("base_link", "base_link_frd"), ("base_link", "altimeter_link"),
                      ("base_link", "dvl_link"), ("base_link", "fls_link")}
    by_child = {t.child_frame_id: t.transform for _, m in topics["/tf_static"] for t in m.transforms}

    def flu(v):  # FRD -> FLU by an axis swap
        return [v[0], -v[1], -v[2]]

    def matrix(tf):
        q = tf.rotation
        return Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix()

    for child, pos in (("altimeter_link", ALT_POS_FRD_M), ("dvl_link", DVL_POS_FRD_M)):
        t = by_child[child].translation
        np.testing.assert_allclose([t.x, t.y, t.z], flu(pos), atol=1e-12)
    # Range convention: x along the beam; a +20 deg pitch turns the down-looking beam forward
    th = np.deg2rad(ALT_PITCH_DEG)
    np.testing.assert_allclose(matrix(by_child["altimeter_link"])[:, 0], flu([np.sin(th), 0.0, np.cos(th)]),
                               atol=1e-12)
    np.testing.assert_allclose(matrix(by_child["dvl_link"]), np.diag([1.0, -1.0, -1.0]), atol=1e-12)  # FRD axes
    dynamic = {(t.header.frame_id, t.child_frame_id) for t in topics["/tf"][-1][1].transforms}
    assert dynamic == {("map", "base_link_truth"), ("odom", "base_link")}
    tf = next(t for _, m in topics["/tf_static"] for t in m.transforms if t.child_frame_id == "fls_link")
    q = tf.transform.rotation
    R = Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix()
    tilt = np.deg2rad(15.0)  # cssn_lawnmower: the sonar looks forward, 15 deg down
    # message z (boresight) is forward and down in FLU; message x is "up" in the fan's vertical plane
    np.testing.assert_allclose(R[:, 2], [np.cos(tilt), 0.0, -np.sin(tilt)], atol=1e-12)
    np.testing.assert_allclose(R[:, 0], [np.sin(tilt), 0.0, np.cos(tilt)], atol=1e-12)


def test_sensor_messages_carry_the_values_delivered(bag_run):
    scn, _, cap, _, _, topics = bag_run
    imu = [m for _, m in topics["/auvsim/imu"]]
    src: list[ImuMsg] = cap.msgs["ImuMsg"]
    np.testing.assert_allclose([[m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z] for m in imu],
                               [[s.rate_body_radps[0], -s.rate_body_radps[1], -s.rate_body_radps[2]] for s in src])
    np.testing.assert_allclose([m.linear_acceleration.z for m in imu], [-s.accel_body_mps2[2] for s in src])
    dvl = [m for _, m in topics["/auvsim/dvl"]]
    dsrc: list[DvlMsg] = cap.msgs["DvlMsg"]
    np.testing.assert_allclose([[m.velocity.x, m.velocity.y, m.velocity.z] for m in dvl],
                               [s.vel_body_mps for s in dsrc])  # dvl_link: the FRD axes as given
    assert {m.header.frame_id for m in dvl} == {"dvl_link"}
    b = dvl[0].beam_unit_vec
    half = np.deg2rad(scn.sensors["dvl"].beam_angle_deg)
    assert [v.z for v in b] == pytest.approx([np.cos(half)] * 4)  # beams tilted from straight down
    pressure = np.array([m.fluid_pressure for _, m in topics["/auvsim/depth"]])
    depth = np.array([s.depth_m for s in cap.msgs["DepthMsg"]])
    np.testing.assert_allclose(pressure, 101325.0 + 1025.0 * 9.81 * depth, rtol=1e-3)
    rng_ = np.array([m.range for _, m in topics["/auvsim/altimeter"]])
    alt = [s for s in cap.msgs["AltimeterMsg"]]
    np.testing.assert_allclose(rng_, [s.altitude_m if s.valid else math.inf for s in alt], rtol=1e-6)


def test_sonar_image_layout_and_beams(bag_run):
    scn, _, cap, _, _, topics = bag_run
    renders: list[FlsRender] = cap.msgs["FlsRender"]
    geo = resolve_geometry(scn.sensors["fls"])
    assert len(renders) == len(topics["/auvsim/fls/image"]) > 0
    for (_, m), r in zip(topics["/auvsim/fls/image"], renders):
        assert m.image.beam_count == geo.n_beams
        img = m.image.data.reshape(geo.n_bins, geo.n_beams)  # one range bin after the other
        np.testing.assert_array_equal(img.T, r.frame.polar)
    d = np.array([[v.x, v.y, v.z] for v in topics["/auvsim/fls/image"][0][1].beam_directions])
    az = geo.beam_azimuths_rad()
    np.testing.assert_allclose(d, np.c_[np.zeros_like(az), np.sin(az), np.cos(az)], atol=1e-12)
    np.testing.assert_allclose(topics["/auvsim/fls/image"][0][1].ranges, geo.bin_centres_m(), rtol=1e-6)


def test_sonar_ping_info_comes_from_the_preset(bag_run):
    """BlueView M900-130 (the scenario's preset): 900 kHz, 130 x 20 deg fan of 1 deg beams; the
    ranges assume 1500 m/s. Every image says so, per beam for the beam widths."""
    scn, _, _, _, _, topics = bag_run
    assert scn.sensors["fls"].preset == "m900_130"
    n_beams = resolve_geometry(scn.sensors["fls"]).n_beams
    for _, m in topics["/auvsim/fls/image"]:
        info = m.ping_info
        assert info.frequency == pytest.approx(900e3)
        assert info.sound_speed == pytest.approx(1500.0)
        np.testing.assert_allclose(info.tx_beamwidths, np.full(n_beams, np.deg2rad(20.0)), rtol=1e-6)
        np.testing.assert_allclose(info.rx_beamwidths, np.full(n_beams, np.deg2rad(1.0)), rtol=1e-6)


def test_detections_and_world_model_conversion():
    store = make_typestore()
    conv = RosConverter(store)
    det = Detection(t_s=2.5, class_name="opi", score=0.75, box_xyxy_px=np.array([10.0, 20.0, 30.0, 60.0]),
                    range_m=10.0, azimuth_rad=np.deg2rad(30.0))

    class _Obj:
        id, class_name = 7, "target"
        pos_ned = np.array([1.0, 2.0, 4.0])
        cov_ned = np.diag([0.04, 0.09, 0.01])

    msg = conv.detections(PerceptionResult(t_s=2.5, detections=(det,)), "fls_link")
    back = store.deserialize_cdr(store.serialize_cdr(msg, "vision_msgs/msg/Detection2DArray"),
                                 "vision_msgs/msg/Detection2DArray")
    d = back.detections[0]
    assert (d.bbox.center.position.x, d.bbox.center.position.y, d.bbox.size_x, d.bbox.size_y) == (20.0, 40.0, 20.0, 40.0)
    assert d.results[0].hypothesis.class_id == "opi" and d.results[0].hypothesis.score == 0.75
    p = d.results[0].pose.pose.position
    assert (p.x, p.y, p.z) == pytest.approx((0.0, 5.0, 10.0 * np.cos(np.deg2rad(30.0))))
    arr = conv.world_model_markers(2.5, [_Obj()], "map")
    back = store.deserialize_cdr(store.serialize_cdr(arr, "visualization_msgs/msg/MarkerArray"),
                                 "visualization_msgs/msg/MarkerArray")
    assert back.markers[0].action == 3  # DELETEALL
    m = back.markers[1]
    assert (m.pose.position.x, m.pose.position.y, m.pose.position.z) == (2.0, 1.0, -4.0)
    assert (m.scale.x, m.scale.y, m.scale.z) == pytest.approx((1.2, 0.8, 0.4))  # 2-sigma, east/north/up


def test_cli_rosbag_flag(tmp_path, capsys):
    from sim.cli import main

    assert main(["run", "cssn_lawnmower", "--out", str(tmp_path / "r"), "--rosbag-fls-every", "0"]) == 2
    assert "--rosbag-fls-every" in capsys.readouterr().err


def test_scenario_outputs_key_writes_a_thinned_bag(tmp_path):
    from sim.mission.run import run_mission

    scn = load_scenario("cssn_lawnmower", ["duration_s=3", "autonomy.atr.detector=none", "outputs.rosbag=true",
                                           "outputs.rosbag_fls_every=2"])
    run_mission(scn, tmp_path / "run", rerun=False, progress=False)
    with Reader(tmp_path / "run" / "rosbag") as reader:
        n_images = sum(1 for c, _, _ in reader.messages() if c.topic == "/auvsim/fls/image")
    n_frames = int(scn.duration_s * scn.sensors["fls"].rate_hz + 1e-9)  # frames at 0, 1/rate, ... < duration
    assert n_frames >= 6 and n_images == (n_frames + 1) // 2
    run_mission(scn, tmp_path / "off", rerun=False, progress=False, rosbag=False)  # the argument wins
    assert not (tmp_path / "off" / "rosbag").exists()


def test_scenario_outputs_key_is_validated(tmp_path, capsys):
    from sim.cli import main

    assert main(["validate", "cssn_lawnmower", "--set", "outputs.rosbag_fls_every=0"]) == 2
    assert "outputs.rosbag_fls_every" in capsys.readouterr().err


def test_extra_vehicles_get_their_true_odometry_and_tf(tmp_path):
    """The sea trial's buoy: /auvsim/buoy/truth/odometry and map->buoy_truth are its true
    state at each autonomy step, in ENU."""
    class _Steps(ObserverBase):
        def __init__(self) -> None:
            self.buoy_ned: list = []

        def on_start(self, info) -> None: ...

        def on_step(self, r) -> None:
            self.buoy_ned.append(r.others["buoy"].pos_ned.copy())

        def on_message(self, name, msg) -> None: ...

        def on_end(self, summary) -> None: ...

    scn = load_scenario("cssn_sea_trial", ["duration_s=2", "autonomy.atr.detector=none"])
    steps = _Steps()
    mission = Mission(scn, observers=[steps, RosbagRecorder(tmp_path / "rosbag", fls_every=1000)])
    mission.reset()
    mission.run(progress=False)
    store = make_typestore()
    odo, tf = [], []
    with Reader(tmp_path / "rosbag") as reader:
        for conn, _, raw in reader.messages():
            if conn.topic == "/auvsim/buoy/truth/odometry":
                odo.append(store.deserialize_cdr(raw, conn.msgtype))
            elif conn.topic == "/tf":
                tf += [t for t in store.deserialize_cdr(raw, conn.msgtype).transforms if t.child_frame_id == "buoy_truth"]
    ned = np.array(steps.buoy_ned)
    assert len(ned) >= 10 and len(odo) == len(ned) == len(tf)
    assert {m.child_frame_id for m in odo} == {"buoy_truth"} and {t.header.frame_id for t in tf} == {"map"}
    pos = np.array([[m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z] for m in odo])
    np.testing.assert_allclose(pos, np.c_[ned[:, 1], ned[:, 0], -ned[:, 2]], atol=1e-9)
    np.testing.assert_allclose([[t.transform.translation.x, t.transform.translation.y] for t in tf], pos[:, :2],
                               atol=1e-9)
