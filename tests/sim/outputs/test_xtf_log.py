"""The side-scan pings as an XTF file, read back with ``pyxtf`` and with a reader written
here from the format specification's byte layout ([XTF]), with ``struct`` alone, so the
writer (built on ``pyxtf``'s structures) is not checked only through its own library, and
compared with the pings and the navigation of the run that wrote it.

The reader (:func:`read_xtf`) parses the file header, the channel infos, the packet headers,
sonar ping headers (type 0) with their channel headers and samples, and raw navigation
packets (type 107); other packets are skipped by their byte count. :func:`first_bottom_bin`
and :func:`ground_range_line` are the textbook bottom pick and slant-to-ground range
correction of a side-scan ping over a flat bed. ``scripts/xtf_waterfall.py`` draws the docs'
figure with them."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
import struct

import numpy as np
import pytest

pyxtf = pytest.importorskip("pyxtf")

from autonomy.frames import rot_from_euler  # noqa: E402
from autonomy.geodesy import geodetic_to_ned  # noqa: E402
from scenarios import load_scenario  # noqa: E402
from sim.events.records import ObserverBase  # noqa: E402
from sim.mission import Mission  # noqa: E402
from sim.outputs.xtf_log import XtfRecorder  # noqa: E402
from tests.support import assert_clean_error, run_cli  # noqa: E402

# -- the specification reader ---------------------------------------------------------------

def _layout(table: str) -> tuple[struct.Struct, tuple[str, ...]]:
    """A little-endian, unpadded struct of ``"<code> <Name>"`` lines."""
    codes, names = [], []
    for line in table.strip().splitlines():
        code, name = line.split()
        codes.append(code)
        names.append(name)
    return struct.Struct("<" + "".join(codes)), tuple(names)


# XTFFILEHEADER: 256 bytes, then 6 CHANINFO of 128 bytes (1024 in all)
FILE_HEADER, FILE_HEADER_NAMES = _layout("""
B FileFormat
B SystemType
8s RecordingProgramName
8s RecordingProgramVersion
16s SonarName
H SonarType
64s NoteString
64s ThisFileName
H NavUnits
H NumberOfSonarChannels
H NumberOfBathymetryChannels
B NumberOfSnippetChannels
B NumberOfForwardLookArrays
H NumberOfEchoStrengthChannels
B NumberOfInterferometryChannels
B Reserved1
H Reserved2
f ReferencePointHeight
12s ProjectionType
10s SpheriodType
i NavigationLatency
f OriginY
f OriginX
f NavOffsetY
f NavOffsetX
f NavOffsetZ
f NavOffsetYaw
f MRUOffsetY
f MRUOffsetX
f MRUOffsetZ
f MRUOffsetYaw
f MRUOffsetPitch
f MRUOffsetRoll
""")
CHAN_INFO, CHAN_INFO_NAMES = _layout("""
B TypeOfChannel
B SubChannelNumber
H CorrectionFlags
H UniPolar
H BytesPerSample
I Reserved
16s ChannelName
f VoltScale
f Frequency
f HorizBeamAngle
f TiltAngle
f BeamWidth
f OffsetX
f OffsetY
f OffsetZ
f OffsetYaw
f OffsetPitch
f OffsetRoll
H BeamsPerArray
B SampleFormat
53s ReservedArea2
""")
# every packet starts with these 14 bytes
PACKET_START, PACKET_START_NAMES = _layout("""
H MagicNumber
B HeaderType
B SubChannelNumber
H NumChansToFollow
H Reserved1a
H Reserved1b
I NumBytesThisRecord
""")
# XTFPINGHEADER after the packet start: 256 bytes in all
PING_HEADER, PING_HEADER_NAMES = _layout("""
H Year
B Month
B Day
B Hour
B Minute
B Second
B HSeconds
H JulianDay
I EventNumber
I PingNumber
f SoundVelocity
f OceanTide
I Reserved2
f ConductivityFreq
f TemperatureFreq
f PressureFreq
f PressureTemp
f Conductivity
f WaterTemperature
f Pressure
f ComputedSoundVelocity
f MagX
f MagY
f MagZ
f AuxVal1
f AuxVal2
f AuxVal3
f AuxVal4
f AuxVal5
f AuxVal6
f SpeedLog
f Turbidity
f ShipSpeed
f ShipGyro
d ShipYcoordinate
d ShipXcoordinate
H ShipAltitude
H ShipDepth
B FixTimeHour
B FixTimeMinute
B FixTimeSecond
B FixTimeHsecond
f SensorSpeed
f KP
d SensorYcoordinate
d SensorXcoordinate
H SonarStatus
H RangeToFish
H BearingToFish
H CableOut
f Layback
f CableTension
f SensorDepth
f SensorPrimaryAltitude
f SensorAuxAltitude
f SensorPitch
f SensorRoll
f SensorHeading
f Heave
f Yaw
I AttitudeTimeTag
f DOT
I NavFixMilliseconds
B ComputerClockHour
B ComputerClockMinute
B ComputerClockSecond
B ComputerClockHsec
h FishPositionDeltaX
h FishPositionDeltaY
B FishPositionErrorCode
I OptionalOffset
B CableOutHundredths
6s ReservedSpace2
""")
# XTFPINGCHANHEADER: 64 bytes
CHAN_HEADER, CHAN_HEADER_NAMES = _layout("""
H ChannelNumber
H DownsampleMethod
f SlantRange
f GroundRange
f TimeDelay
f TimeDuration
f SecondsPerPing
H ProcessingFlags
H Frequency
H InitialGainCode
H GainCode
H BandWidth
I ContactNumber
H ContactClassification
B ContactSubNumber
B ContactType
I NumSamples
H MillivoltScale
f ContactTimeOffTrack
B ContactCloseNumber
B Reserved2
f FixedVSOP
h Weight
4s ReservedSpace
""")
# XTFPOSRAWNAVIGATION (type 107) after the packet start: 64 bytes in all
RAW_NAV, RAW_NAV_NAMES = _layout("""
H Year
B Month
B Day
B Hour
B Minute
B Second
H Microsecond
d RawYcoordinate
d RawXcoordinate
d RawAltitude
f Pitch
f Roll
f Heave
f Heading
B Reserved2
""")
MAGIC = 0xFACE
SONAR, RAW_NAVIGATION = 0, 107
SAMPLE_DTYPES = {1: np.uint8, 2: np.uint16, 4: np.uint32}


@dataclass
class SpecPing:
    header: dict
    channels: list[dict]
    samples: list[np.ndarray]


@dataclass
class SpecFile:
    header: dict
    chan_info: list[dict]
    pings: list[SpecPing] = field(default_factory=list)
    navigation: list[dict] = field(default_factory=list)
    other_packets: int = 0


def _unpack(layout: struct.Struct, names: tuple[str, ...], buf: bytes, offset: int) -> dict:
    return dict(zip(names, layout.unpack_from(buf, offset)))


def read_xtf(path: Path) -> SpecFile:
    """Parse an XTF file. Raises ValueError on a bad magic number or a packet past the end."""
    buf = Path(path).read_bytes()
    head = _unpack(FILE_HEADER, FILE_HEADER_NAMES, buf, 0)
    infos = [_unpack(CHAN_INFO, CHAN_INFO_NAMES, buf, 256 + 128 * i) for i in range(6)]
    out = SpecFile(head, infos)
    pos = 1024
    while pos < len(buf):
        start = _unpack(PACKET_START, PACKET_START_NAMES, buf, pos)
        if start["MagicNumber"] != MAGIC:
            raise ValueError(f"no packet magic number at byte {pos}")
        size = start["NumBytesThisRecord"]
        if size < PACKET_START.size or pos + size > len(buf):
            raise ValueError(f"packet at byte {pos} claims {size} bytes")
        body = pos + PACKET_START.size
        if start["HeaderType"] == SONAR:
            ping = _unpack(PING_HEADER, PING_HEADER_NAMES, buf, body)
            ping.update(start)
            at = body + PING_HEADER.size
            channels, samples = [], []
            for i in range(start["NumChansToFollow"]):
                ch = _unpack(CHAN_HEADER, CHAN_HEADER_NAMES, buf, at)
                at += CHAN_HEADER.size
                width = infos[i]["BytesPerSample"]
                n = ch["NumSamples"]
                samples.append(np.frombuffer(buf, SAMPLE_DTYPES[width], n, at).copy())
                at += n * width
                channels.append(ch)
            if at > pos + size:
                raise ValueError(f"ping at byte {pos} overruns its record")
            out.pings.append(SpecPing(ping, channels, samples))
        elif start["HeaderType"] == RAW_NAVIGATION:
            nav = _unpack(RAW_NAV, RAW_NAV_NAMES, buf, body)
            nav.update(start)
            out.navigation.append(nav)
        else:
            out.other_packets += 1
        pos += size
    return out


def ping_time_s(header: dict, start_day_of_year: int = 1) -> float:
    """Seconds since the start of ``start_day_of_year`` of the ping's date, from its time fields."""
    return ((header["JulianDay"] - start_day_of_year) * 86400.0 + header["Hour"] * 3600.0
            + header["Minute"] * 60.0 + header["Second"] + header["HSeconds"] / 100.0)


def first_bottom_bin(port: np.ndarray, starboard: np.ndarray, fraction: float = 0.1) -> int:
    """The first bottom return of a ping: the earlier of the two sides' first samples at least
    ``fraction`` of that side's 99th percentile (the nadir return reaches both sides at once;
    taking the earlier rides over a speckle-dark first bin on one side). -1 if none."""
    firsts = []
    for line in (port, starboard):
        s = np.asarray(line, dtype=float)
        above = np.flatnonzero(s >= max(fraction * np.percentile(s, 99.0), 1e-9))
        if above.size:
            firsts.append(int(above[0]))
    return min(firsts) if firsts else -1


def ground_range_line(samples: np.ndarray, bin_size_m: float, altitude_m: float, n_out: int) -> np.ndarray:
    """The line resampled to ground range over a flat bed: output bin ``j`` at ground range
    ``g = (j + 0.5) bin_size_m`` reads the slant line at ``sqrt(g^2 + h^2)`` (linear
    interpolation between bin centres; 0 past the last slant bin)."""
    g = (np.arange(n_out) + 0.5) * bin_size_m
    slant_bins = np.sqrt(g * g + altitude_m * altitude_m) / bin_size_m - 0.5
    centres = np.arange(len(samples), dtype=float)
    return np.interp(slant_bins, centres, np.asarray(samples, float), right=0.0)


# -- the tests --------------------------------------------------------------------------------

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
    assert PING_HEADER.size + PACKET_START.size == 256 and CHAN_HEADER.size == 64
    assert FILE_HEADER.size <= 256 and CHAN_INFO.size == 128 and RAW_NAV.size + 14 == 64
    f = read_xtf(path)
    assert f.header["FileFormat"] == 0x7B and f.header["NumberOfSonarChannels"] == 2 and f.header["NavUnits"] == 3
    assert [f.chan_info[i]["TypeOfChannel"] for i in range(2)] == [1, 2]
    assert len(f.pings) == len(run.pings) and len(f.navigation) == len(run.records) and f.other_packets == 0
    rec_t = np.array([r.t_s for r in run.records])
    mount = _mount(scn)
    offsets = []
    for i, (p, ping) in enumerate(zip(f.pings, run.pings)):
        assert p.header["PingNumber"] == i
        assert 0.0 <= ping.t_s - ping_time_s(p.header) < 0.01  # hundredths of a second, truncated
        assert p.header["NavFixMilliseconds"] == round(ping.t_s * 1000.0)
        for side in range(2):
            np.testing.assert_array_equal(p.samples[side], ping.lines_u8[side])
        # the true altitude of the transducers above the flat bed at the ping
        k = int(np.searchsorted(rec_t, ping.t_s - 1e-9))
        truth = run.records[min(k, len(rec_t) - 1)].truth
        depth = (np.asarray(truth.pos_ned) + np.asarray(truth.R_nb) @ mount)[2]
        true_bin = (SEABED_DEPTH_M - depth) / ping.bin_size_m
        offsets.append(first_bottom_bin(*p.samples) - true_bin)
    offsets = np.asarray(offsets)
    assert np.max(np.abs(offsets)) <= 2.0, f"first bottom return off by up to {np.max(np.abs(offsets)):.1f} bins"


def test_ground_range_correction_from_the_file_matches_the_simulator_s_own(written):
    path, _, run, _, _ = written
    f = read_xtf(path)
    diffs = []
    for p, ping in zip(f.pings, run.pings):
        assert ping.ground_lines_u8 is not None  # mcm_survey_full: ground_range true
        n = ping.lines_u8.shape[1]
        h = p.header["SensorPrimaryAltitude"]
        bin_m = p.channels[0]["SlantRange"] / p.channels[0]["NumSamples"]
        for side in range(2):
            mine = ground_range_line(p.samples[side], bin_m, h, n)
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
