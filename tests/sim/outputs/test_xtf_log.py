"""The side-scan pings as an XTF file, read back with ``pyxtf`` and with a reader written
here from the format's byte layout (:mod:`tests.sim.outputs.xtf_spec_reader`), and compared
with the pings and the navigation of the run that wrote it."""

from __future__ import annotations

import numpy as np
import pytest

pyxtf = pytest.importorskip("pyxtf")

from autonomy.frames import rot_from_euler  # noqa: E402
from autonomy.geodesy import geodetic_to_ned  # noqa: E402
from scenarios import load_scenario  # noqa: E402
from sim.events.records import ObserverBase  # noqa: E402
from sim.mission import Mission  # noqa: E402
from sim.outputs.xtf_log import XtfRecorder  # noqa: E402
from tests.sim.outputs import xtf_spec_reader as spec  # noqa: E402
from tests.support import assert_clean_error, run_cli  # noqa: E402

SEABED_DEPTH_M = 20.0  # mcm_survey_full's flat seabed


class _Run(ObserverBase):
    sonar_truth = False

    def __init__(self) -> None:
        self.pings, self.records = [], []

    def on_message(self, name, msg) -> None:
        if name == "sss" and type(msg).__name__ == "SssRender":
            self.pings.append(msg.ping)

    def on_step(self, record) -> None:
        self.records.append(record)


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    folder = tmp_path_factory.mktemp("xtf")
    scn = load_scenario("mcm_survey_full", ["duration_s=12"])
    run = _Run()
    m = Mission(scn, observers=[run, XtfRecorder(folder)])
    summary = m.run(progress=False)
    return folder / "sss.xtf", scn, run, summary, None


def _mount(scn) -> np.ndarray:
    return np.asarray(scn.sensors["sss"].mount_pos_body_m, float)


def test_pyxtf_reads_both_channels_and_every_ping_as_the_sensor_made_it(written):
    path, scn, run, summary, _ = written
    header, packets = pyxtf.xtf_read(str(path))
    assert header.NumberOfSonarChannels == 2
    assert [c.TypeOfChannel for c in header.sonar_info] == [1, 2]  # port, starboard
    pings = packets[pyxtf.XTFHeaderType.sonar]
    assert len(pings) == len(run.pings) == summary.messages_delivered["sss"] > 100
    for got, ping in zip(pings, run.pings):
        np.testing.assert_array_equal(got.data[0], ping.lines_u8[0])
        np.testing.assert_array_equal(got.data[1], ping.lines_u8[1])
        assert got.ping_chan_headers[0].SlantRange == pytest.approx(ping.bin_size_m * ping.lines_u8.shape[1])
    nav = packets[pyxtf.XTFHeaderType.pos_raw_navigation]
    assert len(nav) == len(run.records)


def test_positions_are_the_navigation_at_each_ping_within_the_stated_quantisation(written):
    path, scn, run, _, _ = written
    _, packets = pyxtf.xtf_read(str(path))
    origin = scn.world.origin
    rec_t = np.array([r.t_s for r in run.records])
    mount = _mount(scn)
    worst = 0.0
    for got, ping in zip(packets[pyxtf.XTFHeaderType.sonar], run.pings):
        ned = geodetic_to_ned([got.SensorYcoordinate, got.SensorXcoordinate, 0.0], origin)
        k = int(np.searchsorted(rec_t, ping.t_s - 1e-9))  # the first tick at or after the ping
        nav = run.records[min(k, len(rec_t) - 1)].nav
        expected = np.asarray(nav.pos_ned) + rot_from_euler(*nav.rpy_rad) @ mount
        worst = max(worst, float(np.hypot(*(ned[:2] - expected[:2]))))
        assert got.SensorDepth == pytest.approx(expected[2], abs=0.05)
    # interpolated between ticks 0.1 s apart at under 1 m/s: within 0.1 m of the next tick's estimate
    assert worst < 0.1


def test_the_spec_reader_agrees_with_the_run_and_finds_the_bottom_at_the_altitude_flown(written):
    path, scn, run, _, _ = written
    assert spec.PING_HEADER.size + spec.PACKET_START.size == 256 and spec.CHAN_HEADER.size == 64
    assert spec.FILE_HEADER.size <= 256 and spec.CHAN_INFO.size == 128 and spec.RAW_NAV.size + 14 == 64
    f = spec.read_xtf(path)
    assert f.header["FileFormat"] == 0x7B and f.header["NumberOfSonarChannels"] == 2 and f.header["NavUnits"] == 3
    assert [f.chan_info[i]["TypeOfChannel"] for i in range(2)] == [1, 2]
    assert len(f.pings) == len(run.pings) and len(f.navigation) == len(run.records) and f.other_packets == 0
    rec_t = np.array([r.t_s for r in run.records])
    mount = _mount(scn)
    offsets = []
    for i, (p, ping) in enumerate(zip(f.pings, run.pings)):
        assert p.header["PingNumber"] == i
        assert 0.0 <= ping.t_s - spec.ping_time_s(p.header) < 0.01  # hundredths of a second, truncated
        assert p.header["NavFixMilliseconds"] == round(ping.t_s * 1000.0)
        for side in range(2):
            np.testing.assert_array_equal(p.samples[side], ping.lines_u8[side])
        # the true altitude of the transducers above the flat bed at the ping
        k = int(np.searchsorted(rec_t, ping.t_s - 1e-9))
        truth = run.records[min(k, len(rec_t) - 1)].truth
        depth = (np.asarray(truth.pos_ned) + np.asarray(truth.R_nb) @ mount)[2]
        true_bin = (SEABED_DEPTH_M - depth) / ping.bin_size_m
        offsets.append(spec.first_bottom_bin(*p.samples) - true_bin)
    offsets = np.asarray(offsets)
    assert np.max(np.abs(offsets)) <= 2.0, f"first bottom return off by up to {np.max(np.abs(offsets)):.1f} bins"


def test_ground_range_correction_from_the_file_matches_the_simulator_s_own(written):
    path, _, run, _, _ = written
    f = spec.read_xtf(path)
    diffs = []
    for p, ping in zip(f.pings, run.pings):
        assert ping.ground_lines_u8 is not None  # mcm_survey_full: ground_range true
        n = ping.lines_u8.shape[1]
        h = p.header["SensorPrimaryAltitude"]
        bin_m = p.channels[0]["SlantRange"] / p.channels[0]["NumSamples"]
        for side in range(2):
            mine = spec.ground_range_line(p.samples[side], bin_m, h, n)
            diffs.append(np.abs(mine - ping.ground_lines_u8[side].astype(float)))
    assert np.max(diffs) < 1.01  # the simulator truncates to integers; the altitude is float32 in the file


def test_a_scenario_without_a_side_scan_is_refused_with_one_line_and_nothing_written(tmp_path, capsys):
    out = tmp_path / "run"
    code, err = run_cli(["run", "cssn_lawnmower", "--set", "duration_s=2", "--xtf", "--no-rerun", "--out", str(out)],
                        capsys)
    assert_clean_error(code, err, "--xtf", "sss")
    assert len(err.strip().splitlines()) == 1 and not out.exists()
    code, err = run_cli(["run", "cssn_lawnmower", "--set", "duration_s=2", "--set", "outputs.xtf=true",
                         "--no-rerun", "--out", str(out)], capsys)
    assert_clean_error(code, err, "outputs.xtf")
    assert not out.exists()


def test_the_cli_writes_the_file_where_the_docs_say(tmp_path, capsys):
    out = tmp_path / "run"
    code, _ = run_cli(["run", "mcm_survey_full", "--set", "duration_s=1", "--xtf", "--no-rerun", "--quiet",
                       "--out", str(out)], capsys)
    assert code == 0
    header, packets = pyxtf.xtf_read(str(out / "xtf" / "sss.xtf"))
    assert header.NumberOfSonarChannels == 2 and len(packets[pyxtf.XTFHeaderType.sonar]) >= 10


def test_the_recorder_refuses_a_mission_without_a_side_scan(tmp_path):
    m = Mission(load_scenario("cssn_lawnmower", ["duration_s=1"]), observers=[XtfRecorder(tmp_path / "x")])
    with pytest.raises(ValueError, match="sss"):
        m.run(progress=False)
