"""The side-scan pings of a run as an eXtended Triton Format (XTF) file, the format every
side-scan tool reads ([XTF]).

One file per sensor of kind ``sss``: ``OUT/xtf/<sensor>.xtf``. Its packets are built with the
``pyxtf`` package's structures (``XTFFileHeader``, ``XTFPingHeader``, ``XTFPingChanHeader``,
``XTFPosRawNavigation``; little-endian, packed, as the specification lays them out):

- a 1024-byte file header: two sonar channels (``ChanInfo[0]`` port, ``ChanInfo[1]``
  starboard; one unsigned byte per sample, ``SampleFormat`` 8, stored as slant range),
  navigation units latitude / longitude (``NavUnits`` 3), the sonar's along-track beam angle,
  depression and vertical beam width;
- one sonar ping packet (``HeaderType`` 0) per ping, in time order, padded to a multiple of
  64 bytes: time, ping number, sound speed, position, depth, altitude, heading, pitch, roll,
  speed, then per channel a 64-byte channel header (slant range, ground range, recording
  duration, time between pings, sample count) and the ping's display samples
  (:attr:`autonomy.messages.SssPing.lines_u8`, sample ``k`` at slant range
  ``[k, k + 1) * bin_size_m``, nearest first on both sides);
- one raw navigation packet (``HeaderType`` 107) per autonomy tick.

What the fields hold, and their quantisation:

| field | value | quantisation |
|---|---|---|
| ``Sensor{Y,X}coordinate``, ``Ship{Y,X}coordinate`` | latitude, longitude (deg, WGS-84) of the transducers from the run's navigation estimate, interpolated to the ping time (:mod:`autonomy.geodesy`) | float64: below 1 um |
| ``SensorDepth`` | navigation depth of the transducers, m | float32 |
| ``SensorPrimaryAltitude`` | the ping's first bottom return (:attr:`SssPing.altitude_m`), m; 0 without one | float32 |
| ``SensorHeading``, ``SensorPitch``, ``SensorRoll`` | navigation attitude, deg (heading 0-360) | float32 |
| ``SensorSpeed``, ``ShipSpeed`` | navigation speed over ground, knots | float32 |
| ``SoundVelocity`` | the sonar's ``sound_speed_mps`` (the full speed, not half of it) | float32 |
| date and time | ``start_utc`` + the ping time | 10 ms, truncated (``HSeconds``); ``NavFixMilliseconds`` and ``AttitudeTimeTag`` hold the time since the start in ms |
| ``SlantRange`` / ``GroundRange`` | ``range_max_m`` / its ground range at the ping's altitude | float32 |
| ``TimeDuration`` / ``SecondsPerPing`` | ``2 range_max_m / sound_speed_mps`` / ``1 / rate_hz`` | float32 |

The raw navigation packets hold the vehicle's reference point: ``RawYcoordinate`` /
``RawXcoordinate`` latitude / longitude, ``RawAltitude`` its WGS-84 ellipsoidal height (minus
the depth below the origin's height, not the altitude above the seabed), roll, pitch,
heading; their ``Microsecond`` field counts 0.1 ms (0-9999, a 16-bit field cannot count a
second in microseconds; ``pyxtf``'s ``get_time`` reads it as microseconds, so its times of
these packets are 100 times too fine below the second).

Not simulated, written as 0: transmit frequency, gain codes, the channel offsets (the
transducer position is written directly: the navigation position plus the mount offset
rotated by the navigation attitude).
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass
from datetime import datetime, timedelta, timezone
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from autonomy.frames import rot_from_euler, wrap_angle
from autonomy.geodesy import GeodeticOrigin, ned_to_geodetic
from autonomy.messages import NavEstimate
from sim.events.records import MissionInfo, MissionSummary, ObserverBase, StepRecord

MPS_TO_KNOTS = 3600.0 / 1852.0
#: Default date and time of the simulated t = 0 (the simulation has no wall clock of its own).
DEFAULT_START_UTC = datetime(2026, 1, 1, tzinfo=timezone.utc)
PACKET_ALIGN_BYTES = 64  # ping packets padded to a multiple of this ([XTF])


@dataclass(frozen=True, slots=True)
class NavSample:
    """The navigation estimate at one time: position (3,) NED m, attitude (3,) rad, speed m/s."""

    t_s: float
    pos_ned: np.ndarray
    rpy_rad: np.ndarray
    speed_mps: float

    @classmethod
    def of(cls, nav: NavEstimate, t_s: float) -> "NavSample":
        return cls(float(t_s), np.asarray(nav.pos_ned, float).copy(), np.asarray(nav.rpy_rad, float).copy(),
                   float(np.linalg.norm(np.asarray(nav.vel_body_mps, float)[:2])))

    def at(self, other: "NavSample", t_s: float) -> "NavSample":
        """Linear interpolation from ``self`` to ``other`` at ``t_s`` (angles on the short way round)."""
        span = other.t_s - self.t_s
        w = 0.0 if span <= 0.0 else min(max((t_s - self.t_s) / span, 0.0), 1.0)
        d_rpy = wrap_angle(other.rpy_rad - self.rpy_rad)
        return NavSample(float(t_s), self.pos_ned + w * (other.pos_ned - self.pos_ned), self.rpy_rad + w * d_rpy,
                         self.speed_mps + w * (other.speed_mps - self.speed_mps))


def _set_time(packet: Any, when: datetime, *, hundredths: bool) -> None:
    packet.Year, packet.Month, packet.Day = when.year, when.month, when.day
    packet.Hour, packet.Minute, packet.Second = when.hour, when.minute, when.second
    if hundredths:
        packet.HSeconds = when.microsecond // 10_000
        packet.JulianDay = when.timetuple().tm_yday
    else:
        packet.Microsecond = when.microsecond // 100  # the raw navigation packet's field counts 0.1 ms ([XTF])


class XtfWriter:
    """One side-scan sonar's XTF file.

    Args:
        path: file to write (created or replaced).
        sensor_cfg: the sonar's :class:`scenarios.config.sss.SssConfig`.
        mount_pos_body_m: (3,) FRD position of the transducers, m.
        origin: the mission's geodetic origin.
        start_utc: date and time of t = 0.
        sonar_name: written into the file header (16 bytes at most).
    """

    def __init__(self, path: Path, sensor_cfg: Any, mount_pos_body_m: np.ndarray, origin: GeodeticOrigin,
                 start_utc: datetime = DEFAULT_START_UTC, sonar_name: str = "auvsim sss") -> None:
        from pyxtf import XTFChannelType, XTFFileHeader, XTFNavUnits

        self.cfg = sensor_cfg
        self.mount_pos_body_m = np.asarray(mount_pos_body_m, float)
        self.origin = origin
        self.start_utc = start_utc
        self.n_pings = 0
        self.n_nav = 0
        header = XTFFileHeader()
        header.RecordingProgramName = b"auvsim"
        header.RecordingProgramVersion = b"0.1"
        header.SonarName = sonar_name.encode()[:16]
        header.NoteString = b"simulated side-scan (auvsim)"
        header.ThisFileName = Path(path).name.encode()[:64]
        header.NavUnits = XTFNavUnits.latlon.value
        header.NumberOfSonarChannels = 2
        for i, (kind, name) in enumerate(((XTFChannelType.port, b"port"), (XTFChannelType.stbd, b"starboard"))):
            ch = header.ChanInfo[i]
            ch.TypeOfChannel = kind.value
            ch.SubChannelNumber = i
            ch.CorrectionFlags = 1  # stored as slant range
            ch.UniPolar = 1
            ch.BytesPerSample = 1
            ch.SampleFormat = 8  # unsigned byte
            ch.Reserved = int(sensor_cfg.n_bins)  # samples per ping, for readers older than NumSamples
            ch.ChannelName = name
            ch.HorizBeamAngle = float(sensor_cfg.along_track_beamwidth_deg)
            ch.TiltAngle = float(sensor_cfg.depression_deg)
            ch.BeamWidth = float(sensor_cfg.vertical_beamwidth_deg)
        self._file: BinaryIO = open(path, "wb")  # noqa: SIM115 (closed by close())
        self._file.write(bytes(header))

    # ------------------------------------------------------------------ packets
    def transducer_ned(self, nav: NavSample) -> np.ndarray:
        """(3,) NED position of the transducers, m: the navigation position plus the mount offset."""
        return nav.pos_ned + rot_from_euler(*nav.rpy_rad) @ self.mount_pos_body_m

    def write_tick(self, pings: list[tuple[Any, NavSample]], nav: NavSample) -> None:
        """Append ``pings`` (each with the navigation at its time), then one navigation packet
        of ``nav``; the geodetic conversions of a tick are done in one call."""
        points = np.array([self.transducer_ned(n) for _, n in pings] + [nav.pos_ned])
        geo = ned_to_geodetic(points, self.origin)
        for (ping, at), g, pos in zip(pings, geo, points):
            self.write_ping(ping, at, (g, float(pos[2])))
        self.write_navigation(nav, geo[-1])

    def write_ping(self, ping: Any, nav: NavSample, geodetic: tuple[np.ndarray, float] | None = None) -> None:
        """Append one :class:`autonomy.messages.SssPing` with the navigation at its time
        (``geodetic``: the transducers' (3,) latitude, longitude, height and depth, if known)."""
        from pyxtf import XTFPingChanHeader, XTFPingHeader

        lines = np.ascontiguousarray(ping.lines_u8, dtype=np.uint8)
        n_bins = int(lines.shape[1])
        cfg = self.cfg
        head = XTFPingHeader()
        head.NumChansToFollow = 2
        body = ctypes.sizeof(XTFPingHeader) + 2 * (ctypes.sizeof(XTFPingChanHeader) + n_bins)
        size = -(-body // PACKET_ALIGN_BYTES) * PACKET_ALIGN_BYTES
        head.NumBytesThisRecord = size
        _set_time(head, self.start_utc + timedelta(seconds=float(ping.t_s)), hundredths=True)
        head.PingNumber = self.n_pings
        head.SoundVelocity = float(cfg.sound_speed_mps)
        if geodetic is None:
            pos = self.transducer_ned(nav)
            geodetic = (ned_to_geodetic(pos, self.origin), float(pos[2]))
        (lat, lon, _), depth = geodetic
        head.SensorYcoordinate = head.ShipYcoordinate = float(lat)
        head.SensorXcoordinate = head.ShipXcoordinate = float(lon)
        head.SensorDepth = depth
        altitude = float(ping.altitude_m)
        head.SensorPrimaryAltitude = altitude if np.isfinite(altitude) else 0.0
        heading_deg = float(np.degrees(nav.rpy_rad[2])) % 360.0
        head.SensorHeading = head.ShipGyro = heading_deg
        head.SensorPitch = float(np.degrees(nav.rpy_rad[1]))
        head.SensorRoll = float(np.degrees(nav.rpy_rad[0]))
        head.SensorSpeed = head.ShipSpeed = nav.speed_mps * MPS_TO_KNOTS
        ms = int(round(float(ping.t_s) * 1000.0))
        head.NavFixMilliseconds = head.AttitudeTimeTag = ms
        slant = float(n_bins * ping.bin_size_m)
        ground = float(np.sqrt(max(slant**2 - altitude**2, 0.0))) if np.isfinite(altitude) else 0.0
        parts = [bytes(head)]
        for channel in range(2):
            ch = XTFPingChanHeader()
            ch.ChannelNumber = channel
            ch.SlantRange = slant
            ch.GroundRange = ground
            ch.TimeDuration = 2.0 * slant / float(cfg.sound_speed_mps)
            ch.SecondsPerPing = 1.0 / float(cfg.rate_hz)
            ch.NumSamples = n_bins
            parts.append(bytes(ch))
            parts.append(lines[channel].tobytes())
        packet = b"".join(parts)
        self._file.write(packet + bytes(size - len(packet)))
        self.n_pings += 1

    def write_navigation(self, nav: NavSample, geodetic: np.ndarray | None = None) -> None:
        """Append one raw navigation packet (``HeaderType`` 107) of the vehicle's reference point
        (``geodetic``: its (3,) latitude, longitude, height, if known)."""
        from pyxtf import XTFPosRawNavigation

        p = XTFPosRawNavigation()
        p.NumBytesThisRecord = ctypes.sizeof(XTFPosRawNavigation)
        _set_time(p, self.start_utc + timedelta(seconds=nav.t_s), hundredths=False)
        lat, lon, height = ned_to_geodetic(nav.pos_ned, self.origin) if geodetic is None else geodetic
        p.RawYcoordinate, p.RawXcoordinate, p.RawAltitude = float(lat), float(lon), float(height)
        p.Roll, p.Pitch = (float(np.degrees(v)) for v in nav.rpy_rad[:2])
        p.Heading = float(np.degrees(nav.rpy_rad[2])) % 360.0
        self._file.write(bytes(p))
        self.n_nav += 1

    def close(self) -> None:
        self._file.close()


class XtfRecorder(ObserverBase):
    """Writes every side-scan ping of a run into ``folder/<sensor>.xtf`` (:class:`XtfWriter`),
    with the navigation estimate interpolated to each ping's time, and one navigation packet
    per autonomy tick.

    Args:
        folder: where the files go (created at the start).
        start_utc: date and time of t = 0 (default :data:`DEFAULT_START_UTC`).

    Raises:
        ValueError: (at :meth:`on_start`) the mission has no sensor of kind ``sss``.
    """

    sonar_frames = False  # reads no forward-looking sonar frame
    sonar_truth = False

    def __init__(self, folder: Path, start_utc: datetime = DEFAULT_START_UTC) -> None:
        self.folder = Path(folder)
        self.start_utc = start_utc
        self._writers: dict[str, XtfWriter] = {}
        self._pending: list[tuple[str, Any]] = []
        self._prev: NavSample | None = None

    def on_start(self, info: MissionInfo) -> None:
        names = [n for n, kind in info.sensors.items() if kind == "sss"]
        if not names:
            raise ValueError("xtf: the scenario has no sensor of kind sss (a side-scan sonar)")
        from sim.sensors.sss import SssRender  # the scenario has a side-scan: its module loads anyway

        self._render_type = SssRender
        self.close()
        self.folder.mkdir(parents=True, exist_ok=True)
        sensors = info.scenario.sensors
        for name in names:
            cfg = sensors[name]
            self._writers[name] = XtfWriter(self.folder / f"{name}.xtf", cfg, info.sensor_mounts[name].pos_body_m,
                                            info.scenario.world.origin, self.start_utc, sonar_name=name)
        self._pending.clear()
        self._prev = None

    def on_message(self, name: str, msg: Any) -> None:
        if name in self._writers and isinstance(msg, self._render_type):
            self._pending.append((name, msg.ping))

    def on_step(self, record: StepRecord) -> None:
        nav = NavSample.of(record.nav, record.t_s)
        prev = self._prev if self._prev is not None else nav
        for name, writer in self._writers.items():
            writer.write_tick([(ping, prev.at(nav, ping.t_s)) for n, ping in self._pending if n == name], nav)
        self._pending.clear()
        self._prev = nav

    def on_end(self, summary: MissionSummary) -> None:
        if self._prev is not None:
            for name, ping in self._pending:
                self._writers[name].write_ping(ping, self._prev)
        self._pending.clear()
        self.close()

    def close(self) -> None:
        for w in self._writers.values():
            w.close()

    @property
    def counts(self) -> dict[str, int]:
        """Pings written per sensor."""
        return {n: w.n_pings for n, w in self._writers.items()}
