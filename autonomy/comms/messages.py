"""The binary messages of the two-vehicle system (paper 000 section VII, docs/references.md [P000]).

Two messages, framed by :mod:`autonomy.comms.wire` (version, type, CRC-16; big-endian).
The tables are protocol version 2, which encoders write; version 1 (still decoded, and
written on request for receivers that read only it) differs only in the depth field, an i16
in cm (two bytes, -327.68 to 327.67 m), so its fields after the depth sit one byte earlier
and its messages are one byte shorter (32 and 37 bytes).

**Detection** (type 1, AUV -> buoy, 33 bytes): what paper 000 sent for each ATR detection
(its reliability, the absolute time, and latitude / longitude / depth from the box and the
AUV's navigation), plus the position covariance summary and the class.

====  =====  ====================================================================
byte  type   field
====  =====  ====================================================================
0     u8     protocol version (2)
1     u8     message type (1)
2     u16    detection id (wraps at 65536)
4     u32    time, UNIX seconds (UTC)
8     u16    time, milliseconds
10    i32    latitude, 1e-7 deg
14    i32    longitude, 1e-7 deg
18    i24    depth below the origin's height, cm (-83886.08 to 83886.07 m)
21    7 B    covariance summary (:class:`autonomy.comms.wire.CovSummary`)
28    u8     class id (index into the sender's class table)
29    u8     class probability (of that class), 1/255
30    u8     reliability (the ATR's detection probability), 1/255
31    u16    CRC-16/CCITT-FALSE of bytes 0-30
====  =====  ====================================================================

**USBL fix** (type 2, buoy -> AUV, 38 bytes): the buoy's USBL fix of the AUV (the paper's
future work: the buoy's USBL improving the AUV's navigation).

====  =====  ====================================================================
byte  type   field
====  =====  ====================================================================
0     u8     protocol version (2)
1     u8     message type (2)
2     u16    fix id (wraps at 65536)
4     u32    measurement time, UNIX seconds (UTC)
8     u16    measurement time, milliseconds
10    i32    AUV latitude, 1e-7 deg
14    i32    AUV longitude, 1e-7 deg
18    i24    AUV depth below the origin's height, cm
21    7 B    covariance summary of the AUV fix (USBL and buoy GNSS errors together)
28    i32    buoy GNSS latitude, 1e-7 deg
32    i32    buoy GNSS longitude, 1e-7 deg
36    u16    CRC-16/CCITT-FALSE of bytes 0-35
====  =====  ====================================================================

Round-trip error bounds are those of the fields (:mod:`autonomy.comms.wire`): 0.5 ms,
5e-8 deg, 5 mm depth, 0.5 mm per sigma, 0.35 deg ellipse azimuth, 1/510 per probability.
:func:`decode` raises ``ValueError`` on a packet that is truncated, corrupt (CRC), of
an unknown protocol version or of an unknown type; ``encode`` raises ``ValueError`` naming
a field its version cannot hold (:func:`autonomy.comms.wire.depth_range_m`).
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from autonomy.comms import wire
from autonomy.comms.wire import CovSummary
from autonomy.geodesy import GeodeticOrigin, lat_lon_depth_to_ned, ned_to_lat_lon_depth
from autonomy.localization.geolocate import LocalizedDetection

FloatArray = NDArray[np.float64]

DETECTION_TYPE = 1
USBL_FIX_TYPE = 2
_ID = struct.Struct(">H")
_TAIL = struct.Struct(">BBB")  # class id, class probability, reliability
_BASE_SIZES = {DETECTION_TYPE: 30, USBL_FIX_TYPE: 35}  # without the depth field's bytes
#: (version, type) -> packet size, bytes.
SIZES = {(v, t): n + wire.DEPTH_BYTES[v] for v in wire.VERSIONS for t, n in _BASE_SIZES.items()}
#: Sizes of the version encoders write.
DETECTION_SIZE_BYTES = SIZES[(wire.PROTOCOL_VERSION, DETECTION_TYPE)]
USBL_FIX_SIZE_BYTES = SIZES[(wire.PROTOCOL_VERSION, USBL_FIX_TYPE)]


def message_size_bytes(msg_type: int, version: int = wire.PROTOCOL_VERSION) -> int:
    """Size (bytes) of a ``msg_type`` packet (:data:`DETECTION_TYPE`, :data:`USBL_FIX_TYPE`) in ``version``."""
    return SIZES[(wire.check_version(version), msg_type)]


def _fix_body(msg_id: int, t_unix_s: float, lat_deg: float, lon_deg: float, depth_m: float,
              cov_ned: FloatArray, version: int, saturate: bool) -> bytes:
    if not 0 <= msg_id <= 0xFFFF:
        raise ValueError(f"message id must be in [0, 65535], got {msg_id}")
    return (_ID.pack(msg_id) + wire.pack_time(t_unix_s) + wire.pack_lat_lon(lat_deg, lon_deg)
            + wire.pack_depth(depth_m, version) + CovSummary.from_cov_ned(cov_ned).pack(saturate))


def _read_fix(body: bytes, version: int) -> tuple[int, float, float, float, float, FloatArray, int]:
    """(id, time, lat, lon, depth, cov, offset after the covariance) of a fix body."""
    (msg_id,) = _ID.unpack_from(body, 0)
    t = wire.unpack_time(body, 2)
    lat, lon = wire.unpack_lat_lon(body, 8)
    depth = wire.unpack_depth(body, 16, version)
    off = 16 + wire.DEPTH_BYTES[version]
    cov = CovSummary.unpack(body, off).cov_ned()
    return msg_id, t, lat, lon, depth, cov, off + wire.COV_SIZE


@dataclass(frozen=True, slots=True)
class DetectionReport:
    """One ATR detection as sent to the surface.

    Attributes:
        detection_id: sender's detection counter, 0..65535.
        t_unix_s: frame time, UNIX seconds (UTC).
        lat_deg, lon_deg: WGS-84 position, deg.
        depth_m: metres below the origin's ellipsoidal height (:mod:`autonomy.geodesy`).
        cov_ned: (3, 3) position covariance in the local NED frame, m^2 (decoded: the
            block-diagonal summary).
        class_id: index into the sender's class-name table, 0..255.
        class_prob: probability of that class, in [0, 1].
        reliability: the ATR's probability that the detection is a real object, in [0, 1].
    """

    detection_id: int
    t_unix_s: float
    lat_deg: float
    lon_deg: float
    depth_m: float
    cov_ned: FloatArray
    class_id: int
    class_prob: float
    reliability: float

    def encode(self, version: int = wire.PROTOCOL_VERSION, saturate: bool = True) -> bytes:
        """The packet in protocol ``version`` (33 bytes in version 2, 32 in version 1);
        ``saturate``: sigmas beyond the covariance field are sent as its largest value
        (else they raise).

        Raises:
            ValueError: a field out of its range in that version (named), or an unknown version.
        """
        if not 0 <= self.class_id <= 255:
            raise ValueError(f"class_id must be in [0, 255], got {self.class_id}")
        body = _fix_body(self.detection_id, self.t_unix_s, self.lat_deg, self.lon_deg, self.depth_m, self.cov_ned,
                         wire.check_version(version), saturate)
        tail = _TAIL.pack(self.class_id, wire.pack_prob(self.class_prob, "class_prob"),
                          wire.pack_prob(self.reliability, "reliability"))
        return wire.frame(DETECTION_TYPE, body + tail, version)

    @classmethod
    def from_localized(cls, det: LocalizedDetection, detection_id: int, origin: GeodeticOrigin,
                       epoch_unix_s: float, class_names: Sequence[str]) -> "DetectionReport":
        """The report of a geolocated detection (mission time ``det.t_s`` + ``epoch_unix_s``).

        The ATR score becomes the reliability; ``class_prob`` is 1 (the ATR gives one label).

        Raises:
            ValueError: ``det.class_name`` is not in ``class_names``.
        """
        try:
            class_id = list(class_names).index(det.class_name)
        except ValueError:
            raise ValueError(f"class {det.class_name!r} is not in the message class table {list(class_names)}") from None
        lat, lon, depth = (float(v) for v in ned_to_lat_lon_depth(det.pos_ned, origin))
        return cls(detection_id, epoch_unix_s + det.t_s, lat, lon, depth, np.asarray(det.cov_ned, dtype=float),
                   class_id, 1.0, float(det.class_score))

    def to_localized(self, origin: GeodeticOrigin, epoch_unix_s: float,
                     class_names: Sequence[str]) -> LocalizedDetection:
        """The detection in the receiver's mission frame (what its world model takes).

        Raises:
            ValueError: ``class_id`` is beyond ``class_names``.
        """
        if self.class_id >= len(class_names):
            raise ValueError(f"class id {self.class_id} is beyond the class table {list(class_names)}")
        pos = lat_lon_depth_to_ned([self.lat_deg, self.lon_deg, self.depth_m], origin)
        return LocalizedDetection(self.t_unix_s - epoch_unix_s, pos, np.asarray(self.cov_ned, dtype=float),
                                  self.reliability, class_names[self.class_id])


@dataclass(frozen=True, slots=True)
class UsblFixReport:
    """The buoy's USBL fix of the AUV, sent down to it.

    Attributes:
        fix_id: buoy's fix counter, 0..65535.
        t_unix_s: measurement time, UNIX seconds (UTC).
        lat_deg, lon_deg, depth_m: the AUV's position (depth below the origin's height, m).
        cov_ned: (3, 3) covariance of that position in the local NED frame, m^2.
        buoy_lat_deg, buoy_lon_deg: the buoy's GNSS position at the fix, deg.
    """

    fix_id: int
    t_unix_s: float
    lat_deg: float
    lon_deg: float
    depth_m: float
    cov_ned: FloatArray
    buoy_lat_deg: float
    buoy_lon_deg: float

    def encode(self, version: int = wire.PROTOCOL_VERSION, saturate: bool = True) -> bytes:
        """The packet in protocol ``version`` (38 bytes in version 2, 37 in version 1);
        ``saturate`` as :meth:`DetectionReport.encode`.

        Raises:
            ValueError: a field out of its range in that version (named), or an unknown version.
        """
        body = _fix_body(self.fix_id, self.t_unix_s, self.lat_deg, self.lon_deg, self.depth_m, self.cov_ned,
                         wire.check_version(version), saturate)
        return wire.frame(USBL_FIX_TYPE, body + wire.pack_lat_lon(self.buoy_lat_deg, self.buoy_lon_deg), version)

    def pos_ned(self, origin: GeodeticOrigin) -> FloatArray:
        """(3,) the AUV's fixed position in the mission NED frame of ``origin``, m."""
        return lat_lon_depth_to_ned([self.lat_deg, self.lon_deg, self.depth_m], origin)


Message = DetectionReport | UsblFixReport


def decode(data: bytes) -> Message:
    """The message in a packet of either protocol version (:data:`autonomy.comms.wire.VERSIONS`).

    Raises:
        ValueError: truncated, corrupt (CRC), an unknown protocol version or an unknown type.
    """
    version, msg_type, body = wire.unframe(data, SIZES)
    msg_id, t, lat, lon, depth, cov, off = _read_fix(body, version)
    if msg_type == DETECTION_TYPE:
        class_id, class_p, rel = _TAIL.unpack_from(body, off)
        return DetectionReport(msg_id, t, lat, lon, depth, cov, class_id, class_p / wire.PROB_SCALE,
                               rel / wire.PROB_SCALE)
    buoy_lat, buoy_lon = wire.unpack_lat_lon(body, off)
    return UsblFixReport(msg_id, t, lat, lon, depth, cov, buoy_lat, buoy_lon)
