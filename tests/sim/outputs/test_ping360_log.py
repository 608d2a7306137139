"""The scanning sonar's pings as Blue Robotics ping-protocol messages, read back with that
package's own parser (``brping.PingParser``) and against the protocol's byte layout, and
compared with the pings the run made."""

from __future__ import annotations

import csv
import struct

import numpy as np
import pytest

brping = pytest.importorskip("brping")

from scenarios import load_scenario  # noqa: E402
from sim.cli import main  # noqa: E402
from sim.events.records import ObserverBase  # noqa: E402
from sim.mission import Mission  # noqa: E402
from sim.outputs.ping360_log import Ping360LogRecorder  # noqa: E402
from tests.support import assert_clean_error, run_cli  # noqa: E402


class _Pings(ObserverBase):
    sonar_truth = False

    def __init__(self) -> None:
        self.pings = []

    def on_message(self, name, msg) -> None:
        if name == "msis" and type(msg).__name__ == "MsisRender":
            self.pings.append(msg.ping)


@pytest.fixture(scope="module")
def logged(tmp_path_factory):
    folder = tmp_path_factory.mktemp("p360")
    pings = _Pings()
    m = Mission(load_scenario("tank_rectangular", ["duration_s=4"]), observers=[pings, Ping360LogRecorder(folder)])
    summary = m.run(progress=False)
    return folder, pings.pings, summary


def test_every_ping_is_one_device_data_message_the_package_parses(logged):
    folder, pings, summary = logged
    parser, parsed = brping.PingParser(), []
    for b in (folder / "msis.bin").read_bytes():
        if parser.parse_byte(b) == parser.NEW_MESSAGE:
            parsed.append(parser.rx_msg)
    assert len(parsed) == len(pings) == summary.messages_delivered["msis"] > 10
    for msg, ping in zip(parsed, pings):
        assert msg.message_id == brping.definitions.PING360_DEVICE_DATA
        assert msg.angle == round(ping.angle_grad) % 400
        assert msg.sample_period == ping.sample_period_ticks
        assert msg.transmit_duration == round(ping.transmit_duration_us)
        assert msg.number_of_samples == len(ping.intensity) and msg.transmit_frequency == 750
        np.testing.assert_array_equal(np.frombuffer(bytes(msg.data), np.uint8), ping.intensity)


def test_packets_follow_the_protocol_byte_layout_and_the_index(logged):
    """Ping-protocol framing written out here from its specification: 'BR', payload length
    (u16), message id (u16), source and destination ids (u8), the payload (little endian), and
    a u16 checksum of every byte before it."""
    folder, pings, _ = logged
    raw = (folder / "msis.bin").read_bytes()
    with open(folder / "msis.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(pings)
    for row, ping in zip(rows, pings):
        k = int(row["offset_bytes"])
        assert raw[k:k + 2] == b"BR"
        length, msg_id = struct.unpack_from("<HH", raw, k + 2)
        assert msg_id == 2300
        payload = raw[k + 8:k + 8 + length]
        mode, gain, angle, tx_us, period, freq, n, data_len = struct.unpack_from("<BBHHHHHH", payload)
        assert (mode, gain, angle, period, n, data_len) == (1, 0, round(ping.angle_grad) % 400,
                                                             ping.sample_period_ticks, len(ping.intensity),
                                                             len(ping.intensity))
        assert payload[14:] == ping.intensity.tobytes()
        (checksum,) = struct.unpack_from("<H", raw, k + 8 + length)
        assert checksum == sum(raw[k:k + 8 + length]) & 0xFFFF
        assert float(row["t_s"]) == ping.t_s and float(row["angle_grad"]) == ping.angle_grad


def test_cli_writes_the_log_and_refuses_a_scenario_without_a_scanning_sonar(tmp_path, capsys):
    code, err = run_cli(["run", "cssn_lawnmower", "--ping360-log", "--no-rerun", "--out", str(tmp_path / "x")], capsys)
    assert_clean_error(code, err, "--ping360-log", "msis")
    assert not (tmp_path / "x").exists()
    assert main(["run", "pool_circular", "--set", "duration_s=2", "--ping360-log", "--no-rerun", "--quiet",
                 "--out", str(tmp_path / "p")]) == 0
    assert (tmp_path / "p" / "ping360" / "msis.bin").stat().st_size > 0
