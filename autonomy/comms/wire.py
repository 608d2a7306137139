"""Fixed-point fields and framing shared by the acoustic messages.

Framing: every message is ``version (u8) | type (u8) | body | CRC-16 (u16)``, big-endian
(network order). Encoders write :data:`PROTOCOL_VERSION` (2) unless told to write version 1
(for receivers that read only it); decoders read both. The CRC is CRC-16/CCITT-FALSE
(polynomial 0x1021, initial value 0xFFFF, ``binascii.crc_hqx``) over every byte before it;
it detects every error of 1 to 3 bits and every burst up to 16 bits in these short
packets, so a corrupt or truncated packet is rejected instead of decoded into wrong numbers.

Fields and their quantisation (the largest round-trip error):

- time: UNIX seconds (u32) + milliseconds (u16): 0.5 ms; 1970 to 2106.
- latitude, longitude: i32 in 1e-7 deg: 5e-8 deg (5.6 mm north, 5.6 mm x cos(lat) east).
- depth below the origin's height: version 2: i24 (three bytes) in cm, -83886.08 to
  83886.07 m, full-ocean depth (11 km) with room for any seabed the scenarios allow; version
  1: i16 in cm, -327.68 to 327.67 m. Both 5 mm. (Compact AUV formats such as WHOI's CCL and
  its successor DCCL size each field to its bounds and resolution in the same way; cm over
  +-84 km takes 3 bytes, the next byte boundary above the 22 bits that 11 km needs.)
- covariance summary (7 bytes): the horizontal error ellipse (1-sigma semi-axes, u16 mm each,
  and the major axis's azimuth from north in [0, 180) deg, u8 in 180/256 deg steps) and the
  vertical sigma (u16 mm): 0.5 mm on each sigma, 0.35 deg on the azimuth. Sigmas above
  65.535 m are sent as 65.535 m (saturated, never wrapped), or refused with
  ``saturate=False`` (what the mission sends: a saturated sigma would make the receiver
  overconfident; such a message is not sent and is counted). The north/east-down
  correlations are not sent: the decoded covariance is block-diagonal.
- probabilities: u8 in 1/255 steps: 1/510.
"""

from __future__ import annotations

import binascii
import math
import struct
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]

#: The version encoders write; :data:`VERSIONS` are those decoders read.
PROTOCOL_VERSION = 2
VERSIONS = (1, 2)
HEADER = struct.Struct(">BB")
CRC = struct.Struct(">H")
TIME = ">IH"  # UNIX seconds, milliseconds
LAT_LON = ">ii"  # 1e-7 deg
#: Depth field per version: (bytes, signed two's-complement big-endian), in cm.
DEPTH_BYTES = {1: 2, 2: 3}
COV = ">HHHB"  # sigma major, minor, down (mm); major-axis azimuth (180/256 deg)

DEG_SCALE = 1e7
DEPTH_SCALE = 100.0
SIGMA_SCALE = 1000.0
AZIMUTH_STEP_RAD = math.pi / 256.0
PROB_SCALE = 255.0
_U16_MAX = 65535
#: Largest sigma the covariance summary holds, m.
SIGMA_MAX_M = _U16_MAX / SIGMA_SCALE


def crc16(data: bytes) -> int:
    """CRC-16/CCITT-FALSE of ``data`` (check value of b"123456789": 0x29B1)."""
    return binascii.crc_hqx(data, 0xFFFF)


def check_version(version: int) -> int:
    """``version`` if it is one of :data:`VERSIONS`; else ``ValueError``."""
    if version not in VERSIONS:
        raise ValueError(f"acoustic message: protocol version {version}, this codec reads {list(VERSIONS)}")
    return version


def frame(msg_type: int, body: bytes, version: int = PROTOCOL_VERSION) -> bytes:
    """``version | type | body | CRC``."""
    head = HEADER.pack(check_version(version), msg_type) + body
    return head + CRC.pack(crc16(head))


def unframe(data: bytes, sizes: dict[tuple[int, int], int]) -> tuple[int, int, bytes]:
    """(version, type, body) of a framed packet after checking CRC, version, type and length.

    Args:
        data: the packet.
        sizes: (version, message type) -> its total size in bytes.

    Raises:
        ValueError: too short, CRC mismatch (corrupt or truncated), unknown version or type,
            or a length that does not match the type.
    """
    data = bytes(data)
    n = len(data)
    if n < HEADER.size + CRC.size:
        raise ValueError(f"acoustic message: {n} bytes, shorter than the {HEADER.size + CRC.size}-byte frame")
    (crc,) = CRC.unpack_from(data, n - CRC.size)
    if crc != crc16(data[:-CRC.size]):
        raise ValueError(f"acoustic message: CRC-16 mismatch, corrupt or truncated packet ({n} bytes)")
    version, msg_type = HEADER.unpack_from(data)
    check_version(version)
    known = sorted(t for v, t in sizes if v == version)
    if msg_type not in known:
        raise ValueError(f"acoustic message: unknown type {msg_type} (known: {known})")
    size = sizes[(version, msg_type)]
    if n != size:
        raise ValueError(f"acoustic message of type {msg_type} (version {version}): {n} bytes, expected {size}")
    return version, msg_type, data[HEADER.size:-CRC.size]


def _checked_int(value: float, scale: float, lo: int, hi: int, name: str) -> int:
    if not math.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value}")
    q = round(value * scale)
    if not lo <= q <= hi:
        raise ValueError(f"{name} = {value} is outside the encodable range [{lo / scale}, {hi / scale}]")
    return q


def pack_time(t_unix_s: float) -> bytes:
    """Absolute time (UNIX seconds, UTC) as u32 seconds + u16 milliseconds."""
    ms = _checked_int(t_unix_s, 1000.0, 0, 0xFFFFFFFF * 1000 + 999, "t_unix_s")
    s, ms = divmod(ms, 1000)
    return struct.pack(TIME, s, ms)


def unpack_time(body: bytes, offset: int) -> float:
    s, ms = struct.unpack_from(TIME, body, offset)
    if ms > 999:
        raise ValueError(f"acoustic message: millisecond field {ms} > 999")
    return s + ms / 1000.0


def pack_lat_lon(lat_deg: float, lon_deg: float) -> bytes:
    lat = _checked_int(lat_deg, DEG_SCALE, -900_000_000, 900_000_000, "lat_deg")
    lon = _checked_int(lon_deg, DEG_SCALE, -1_800_000_000, 1_800_000_000, "lon_deg")
    return struct.pack(LAT_LON, lat, lon)


def unpack_lat_lon(body: bytes, offset: int) -> tuple[float, float]:
    lat, lon = struct.unpack_from(LAT_LON, body, offset)
    return lat / DEG_SCALE, lon / DEG_SCALE


def depth_range_m(version: int = PROTOCOL_VERSION) -> tuple[float, float]:
    """(shallowest, deepest) depth (m below the origin's height) the version's field holds."""
    half = 1 << (8 * DEPTH_BYTES[check_version(version)] - 1)
    return -half / DEPTH_SCALE, (half - 1) / DEPTH_SCALE


def pack_depth(depth_m: float, version: int = PROTOCOL_VERSION) -> bytes:
    """Depth (m) as the version's signed cm field. Raises ``ValueError`` outside :func:`depth_range_m`."""
    n = DEPTH_BYTES[check_version(version)]
    half = 1 << (8 * n - 1)
    return _checked_int(depth_m, DEPTH_SCALE, -half, half - 1, "depth_m").to_bytes(n, "big", signed=True)


def unpack_depth(body: bytes, offset: int, version: int = PROTOCOL_VERSION) -> float:
    n = DEPTH_BYTES[check_version(version)]
    return int.from_bytes(body[offset:offset + n], "big", signed=True) / DEPTH_SCALE


@dataclass(frozen=True, slots=True)
class CovSummary:
    """Horizontal 1-sigma error ellipse plus vertical sigma of a NED covariance.

    Attributes:
        sigma_major_m, sigma_minor_m: semi-axes of the horizontal ellipse, m.
        major_azimuth_rad: azimuth of the major axis from north towards east, in [0, pi).
        sigma_down_m: sigma along down, m.
    """

    sigma_major_m: float
    sigma_minor_m: float
    major_azimuth_rad: float
    sigma_down_m: float

    @classmethod
    def from_cov_ned(cls, cov_ned: ArrayLike) -> "CovSummary":
        """The summary of a (3, 3) NED covariance (m^2); the N/E-D correlations are dropped.

        Raises:
            ValueError: not a finite, symmetric (3, 3) matrix with non-negative variances.
        """
        c = np.asarray(cov_ned, dtype=float)
        if c.shape != (3, 3):
            raise ValueError(f"cov_ned must be a finite symmetric (3, 3) matrix, got shape {c.shape}")
        (nn, ne, _), (en, ee, _), (_, _, dd) = c.tolist()
        if not all(math.isfinite(v) for v in (nn, ne, en, ee, dd)) or abs(ne - en) > 1e-9 * (abs(nn) + abs(ee)) + 1e-12:
            raise ValueError(f"cov_ned must be a finite symmetric (3, 3) matrix, got {c.tolist()}")
        # eigen-decomposition of the symmetric 2 x 2 horizontal block, closed form
        mid, half_diff = 0.5 * (nn + ee), math.hypot(0.5 * (nn - ee), ne)
        lam_major, lam_minor = mid + half_diff, mid - half_diff
        if dd < 0.0 or lam_minor < -1e-9 * max(1.0, abs(lam_major)):
            raise ValueError(f"cov_ned is not positive semi-definite: variances {nn}, {ee}, {dd}, "
                             f"horizontal eigenvalues {lam_major}, {lam_minor}")
        azimuth = (0.5 * math.atan2(2.0 * ne, nn - ee)) % math.pi
        return cls(math.sqrt(max(lam_major, 0.0)), math.sqrt(max(lam_minor, 0.0)), azimuth, math.sqrt(dd))

    def cov_ned(self) -> FloatArray:
        """The (3, 3) block-diagonal NED covariance it stands for, m^2."""
        ca, sa = math.cos(self.major_azimuth_rad), math.sin(self.major_azimuth_rad)
        r = np.array([[ca, -sa], [sa, ca]])
        out = np.zeros((3, 3))
        out[:2, :2] = r @ np.diag([self.sigma_major_m**2, self.sigma_minor_m**2]) @ r.T
        out[2, 2] = self.sigma_down_m**2
        return out

    def pack(self, saturate: bool = True) -> bytes:
        """The 7 bytes. Sigmas above :data:`SIGMA_MAX_M` are sent as it (``saturate``) or
        raise ``ValueError`` naming the sigma."""
        if not saturate:
            for name in ("sigma_major_m", "sigma_minor_m", "sigma_down_m"):
                if round(getattr(self, name) * SIGMA_SCALE) > _U16_MAX:
                    raise ValueError(f"{name} = {getattr(self, name)} is outside the encodable range "
                                     f"[0, {SIGMA_MAX_M}] (saturating it would understate the error)")

        def mm(sigma: float) -> int:
            return min(round(sigma * SIGMA_SCALE), _U16_MAX)

        az = round(self.major_azimuth_rad / AZIMUTH_STEP_RAD) % 256
        return struct.pack(COV, mm(self.sigma_major_m), mm(self.sigma_minor_m), mm(self.sigma_down_m), az)

    @classmethod
    def unpack(cls, body: bytes, offset: int) -> "CovSummary":
        major, minor, down, az = struct.unpack_from(COV, body, offset)
        return cls(major / SIGMA_SCALE, minor / SIGMA_SCALE, az * AZIMUTH_STEP_RAD, down / SIGMA_SCALE)


COV_SIZE = struct.calcsize(COV)


def pack_prob(p: float, name: str) -> int:
    """A probability in [0, 1] as u8 (1/255 steps). Raises ``ValueError`` outside [0, 1]."""
    if not 0.0 <= p <= 1.0:
        raise ValueError(f"{name} must be in [0, 1], got {p}")
    return round(p * PROB_SCALE)
