"""The ROS 2 bags read by another reader than the one that wrote them: the ``mcap`` library
with its ROS 2 decoder (``mcap-ros2-support``), not ``rosbags``. Every message decodes from the
schema stored in the file, the schemas are the ROS 2 message definitions (the shipped ``.msg``
files; the standard types checked against their published fields), time stamps are monotonic,
and the sonar images decode to the run's frames."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rosbags")  # the writer
mcap_reader = pytest.importorskip("mcap.reader")
mcap_ros2_decoder = pytest.importorskip("mcap_ros2.decoder")

from rosbags.rosbag2 import Reader  # noqa: E402
from scenarios import load_scenario  # noqa: E402
from scenarios.fls_presets import resolve_geometry  # noqa: E402
from sim.events.records import ObserverBase  # noqa: E402
from sim.mission import Mission  # noqa: E402
from sim.ros2bag.recorder import RosbagRecorder  # noqa: E402

ROOT = Path(__file__).resolve().parents[3]
MSG_DIR = ROOT / "sim" / "ros2bag" / "msg"

# Top-level fields of standard ROS 2 messages as published in their packages' .msg files
# (common_interfaces: sensor_msgs, nav_msgs, geometry_msgs), written out here independently.
STANDARD_FIELDS = {
    "sensor_msgs/msg/Imu": [("std_msgs/Header", "header"), ("geometry_msgs/Quaternion", "orientation"),
                            ("float64[9]", "orientation_covariance"), ("geometry_msgs/Vector3", "angular_velocity"),
                            ("float64[9]", "angular_velocity_covariance"),
                            ("geometry_msgs/Vector3", "linear_acceleration"),
                            ("float64[9]", "linear_acceleration_covariance")],
    "sensor_msgs/msg/FluidPressure": [("std_msgs/Header", "header"), ("float64", "fluid_pressure"),
                                      ("float64", "variance")],
    "nav_msgs/msg/Odometry": [("std_msgs/Header", "header"), ("string", "child_frame_id"),
                              ("geometry_msgs/PoseWithCovariance", "pose"),
                              ("geometry_msgs/TwistWithCovariance", "twist")],
    "geometry_msgs/msg/PoseStamped": [("std_msgs/Header", "header"), ("geometry_msgs/Pose", "pose")],
    "tf2_msgs/msg/TFMessage": [("geometry_msgs/TransformStamped[]", "transforms")],
}


class _Frames(ObserverBase):
    sonar_truth = False

    def __init__(self) -> None:
        self.polar: list[np.ndarray] = []

    def on_message(self, name, msg) -> None:
        if name == "fls" and hasattr(msg, "frame") and hasattr(msg.frame, "polar"):
            self.polar.append(msg.frame.polar.copy())


@pytest.fixture(scope="module")
def mcap_run(tmp_path_factory):
    scn = load_scenario("cssn_lawnmower", ["duration_s=3", "autonomy.atr.detector=classical"])
    path = tmp_path_factory.mktemp("mcap") / "bag"
    frames = _Frames()
    Mission(scn, observers=[frames, RosbagRecorder(path)]).run(progress=False)
    (mcap_file,) = path.glob("*.mcap")
    decoded: dict[str, list] = {}
    with open(mcap_file, "rb") as f:
        reader = mcap_reader.make_reader(f, decoder_factories=[mcap_ros2_decoder.DecoderFactory()])
        summary = reader.get_summary()
        for schema, channel, message, msg in reader.iter_decoded_messages(log_time_order=False):
            decoded.setdefault(channel.topic, []).append((message.log_time, msg, schema.name))
    with Reader(path) as reader:  # the writer's library, for the counts
        rosbags_counts = {}
        for connection, _, _ in reader.messages():
            rosbags_counts[connection.topic] = rosbags_counts.get(connection.topic, 0) + 1
    return scn, frames, summary, decoded, rosbags_counts


PRIMITIVES = {"bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16", "int32", "uint32",
              "int64", "uint64", "string", "wstring"}


def _fields(definition: str, package: str | None = None) -> list[tuple[str, str]]:
    """(type, name) of a message definition's fields (constants, comments and the appended
    dependency definitions left out); a type named within ``package`` gets its package."""
    out = []
    for line in definition.split("=" * 80)[0].splitlines():
        line = line.split("#", 1)[0].strip()
        if not line or "=" in line:
            continue
        typ, name = line.split()[:2]
        base = typ.split("[", 1)[0]
        if package is not None and "/" not in base and base not in PRIMITIVES:
            typ = f"{package}/{typ}"
        out.append((typ, name))
    return out


def test_message_counts_equal_what_rosbags_reads(mcap_run):
    *_, decoded, rosbags_counts = mcap_run
    assert {t: len(v) for t, v in decoded.items()} == rosbags_counts
    assert sum(rosbags_counts.values()) > 50


def test_every_message_decodes_from_the_stored_schema(mcap_run):
    _, _, summary, decoded, _ = mcap_run
    counts = summary.statistics.channel_message_counts
    assert len(summary.channels) == len(decoded) >= 10
    for cid, channel in summary.channels.items():
        assert channel.message_encoding == "cdr"
        assert summary.schemas[channel.schema_id].encoding == "ros2msg"
        assert len(decoded[channel.topic]) == counts[cid] > 0


def test_schemas_are_the_ros2_message_definitions(mcap_run):
    _, _, summary, _, _ = mcap_run
    by_name = {s.name: s.data.decode() for s in summary.schemas.values()}
    shipped = {f"{p.parent.parent.name}/msg/{p.stem}": p for p in MSG_DIR.glob("*/msg/*.msg")}
    checked = 0
    for name, text in by_name.items():
        if name in shipped:
            assert _fields(text) == _fields(shipped[name].read_text(), name.split("/")[0]), name
            checked += 1
        if name in STANDARD_FIELDS:
            assert _fields(text) == STANDARD_FIELDS[name], name
            checked += 1
    assert {"marine_acoustic_msgs/msg/ProjectedSonarImage", "marine_acoustic_msgs/msg/Dvl",
            "vision_msgs/msg/Detection2DArray", "sensor_msgs/msg/Imu", "nav_msgs/msg/Odometry"} <= set(by_name)
    assert checked >= 8


def test_time_stamps_are_monotonic(mcap_run):
    _, _, _, decoded, _ = mcap_run
    for topic, items in decoded.items():
        log_ns = [t for t, _, _ in items]
        assert log_ns == sorted(log_ns), topic
        stamped = []  # (log time, the message's first header stamp), ns
        for t, m, _ in items:
            parts = [m] if hasattr(m, "header") else list(getattr(m, "transforms", None) or getattr(m, "markers", []))
            if parts:
                h = parts[0].header
                stamped.append((t, h.stamp.sec * 1_000_000_000 + h.stamp.nanosec))
        assert [s for _, s in stamped] == sorted(s for _, s in stamped), topic
        if topic != "/tf_static":  # a message is logged at its own stamp (simulated time)
            assert all(abs(t - s) <= 1 for t, s in stamped), topic


def test_sonar_images_decode_to_the_runs_frames(mcap_run):
    scn, frames, _, decoded, _ = mcap_run
    images = decoded["/auvsim/fls/image"]
    geo = resolve_geometry(scn.sensors["fls"])
    assert len(images) == len(frames.polar) >= 5
    for (_, m, schema), polar in zip(images, frames.polar):
        assert schema == "marine_acoustic_msgs/msg/ProjectedSonarImage"
        assert m.image.beam_count == geo.n_beams and m.image.dtype == 0  # DTYPE_UINT8
        img = np.frombuffer(bytes(m.image.data), dtype=np.uint8).reshape(geo.n_bins, geo.n_beams)
        np.testing.assert_array_equal(img.T, polar)
        np.testing.assert_allclose(m.ranges, geo.bin_centres_m(), rtol=1e-6)
