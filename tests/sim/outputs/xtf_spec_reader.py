"""A minimal XTF reader written from the format specification's byte layout ([XTF]), with
``struct`` alone, so the simulator's XTF writer (built on ``pyxtf``'s structures) is not
checked only through its own library. It reads the file header, the channel infos, the
packet headers, sonar ping headers (type 0) with their channel headers and samples, and raw
navigation packets (type 107); other packets are skipped by their byte count.

Also :func:`first_bottom_bin` and :func:`ground_range_line`, the textbook slant-to-ground
range correction of a side-scan line over a flat bed.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
import struct

import numpy as np


def _layout(spec: str) -> tuple[struct.Struct, tuple[str, ...]]:
    """A little-endian, unpadded struct of ``"<code> <Name>"`` lines."""
    codes, names = [], []
    for line in spec.strip().splitlines():
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
