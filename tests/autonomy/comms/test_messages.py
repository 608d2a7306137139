"""Binary acoustic messages: sizes, round trips within the stated quantisation, rejection of
truncated and corrupt packets; version 2's depth field to full-ocean depth, version 1 still
decoded (against packets built here from its byte table)."""

from __future__ import annotations

import binascii
import math
import struct

import numpy as np
import pytest

from autonomy.comms import wire
from autonomy.comms.messages import (
    DETECTION_SIZE_BYTES,
    USBL_FIX_SIZE_BYTES,
    DetectionReport,
    UsblFixReport,
    decode,
)
from autonomy.geodesy import GeodeticOrigin, ned_to_lat_lon_depth
from autonomy.localization.geolocate import LocalizedDetection

# the bounds stated in autonomy.comms.wire
T_TOL_S, DEG_TOL, DEPTH_TOL_M, SIGMA_TOL_M, AZ_TOL_RAD, P_TOL = 5e-4, 5e-8, 5e-3, 5e-4, math.pi / 512, 1 / 510
EPS = 1e-9


def _random_cov(rng):
    a = rng.normal(size=(3, 3)) * rng.uniform(0.05, 3.0, 3)
    return a @ a.T + 1e-4 * np.eye(3)


def _random_detection(rng):
    return DetectionReport(
        int(rng.integers(0, 65536)), float(rng.uniform(1.5e9, 2.0e9)), float(rng.uniform(-89.9, 89.9)),
        float(rng.uniform(-180, 180)), float(rng.uniform(-10, 300)), _random_cov(rng), int(rng.integers(0, 256)),
        float(rng.random()), float(rng.random()))


def _horizontal_bound(cov):
    """Largest change of the horizontal block the sigma and azimuth quantisation can cause."""
    w = np.linalg.eigvalsh(cov[:2, :2])
    s = np.sqrt(np.maximum(w, 0))
    return 2 * s[1] * SIGMA_TOL_M + SIGMA_TOL_M**2 + (w[1] - w[0]) * AZ_TOL_RAD + EPS


def test_sizes_and_crc_check_value():
    assert wire.crc16(b"123456789") == 0x29B1  # CRC-16/CCITT-FALSE catalogue check value
    rng = np.random.default_rng(0)
    det = _random_detection(rng)
    assert len(det.encode()) == DETECTION_SIZE_BYTES == 33 and len(det.encode(1)) == 32
    fix = UsblFixReport(1, 1.6e9, 44.0, 9.8, 5.0, np.eye(3), 44.001, 9.801)
    assert len(fix.encode()) == USBL_FIX_SIZE_BYTES == 38 and len(fix.encode(1)) == 37
    assert det.encode()[0] == wire.PROTOCOL_VERSION == 2 and det.encode(1)[0] == 1


def test_detection_round_trip_within_quantisation():
    rng = np.random.default_rng(1)
    for _ in range(500):
        m = _random_detection(rng)
        d = decode(m.encode())
        assert isinstance(d, DetectionReport)
        assert (d.detection_id, d.class_id) == (m.detection_id, m.class_id)
        assert abs(d.t_unix_s - m.t_unix_s) <= T_TOL_S + 1e-6
        assert abs(d.lat_deg - m.lat_deg) <= DEG_TOL + EPS and abs(d.lon_deg - m.lon_deg) <= DEG_TOL + EPS
        assert abs(d.depth_m - m.depth_m) <= DEPTH_TOL_M + EPS
        assert abs(d.class_prob - m.class_prob) <= P_TOL + EPS and abs(d.reliability - m.reliability) <= P_TOL + EPS
        # the decoded covariance is the horizontal block and the down variance of the original
        assert np.max(np.abs(d.cov_ned[:2, :2] - m.cov_ned[:2, :2])) <= _horizontal_bound(m.cov_ned)
        s_d = math.sqrt(m.cov_ned[2, 2])
        assert abs(math.sqrt(d.cov_ned[2, 2]) - s_d) <= SIGMA_TOL_M + EPS
        assert np.all(d.cov_ned[:2, 2] == 0) and np.all(np.linalg.eigvalsh(d.cov_ned) >= 0)


def test_usbl_fix_round_trip_and_position_in_metres():
    origin = GeodeticOrigin()
    rng = np.random.default_rng(2)
    for _ in range(200):
        auv_ned = rng.uniform([-500, -500, 0], [500, 500, 30])
        buoy = ned_to_lat_lon_depth(auv_ned + rng.uniform([-20, -20, 0], [20, 20, 0]) * [1, 1, 0], origin)
        lat, lon, depth = ned_to_lat_lon_depth(auv_ned, origin)
        m = UsblFixReport(int(rng.integers(0, 65536)), float(rng.uniform(1.5e9, 2e9)), lat, lon, depth,
                          _random_cov(rng), buoy[0], buoy[1])
        d = decode(m.encode())
        assert isinstance(d, UsblFixReport) and d.fix_id == m.fix_id
        # 5e-8 deg is 5.6 mm north and 4 mm east here; depth 5 mm
        err = d.pos_ned(origin) - auv_ned
        assert np.hypot(err[0], err[1]) <= 0.0075 and abs(err[2]) <= DEPTH_TOL_M + 1e-6
        assert abs(d.buoy_lat_deg - m.buoy_lat_deg) <= DEG_TOL + EPS
        assert abs(d.buoy_lon_deg - m.buoy_lon_deg) <= DEG_TOL + EPS
        assert np.max(np.abs(d.cov_ned[:2, :2] - m.cov_ned[:2, :2])) <= _horizontal_bound(m.cov_ned)


def test_ellipse_summary_against_a_written_out_case():
    """A 2 m x 0.5 m ellipse with its major axis 30 deg east of north, 0.3 m vertical."""
    az = math.radians(30.0)
    u, v = np.array([math.cos(az), math.sin(az)]), np.array([-math.sin(az), math.cos(az)])
    cov = np.zeros((3, 3))
    cov[:2, :2] = 4.0 * np.outer(u, u) + 0.25 * np.outer(v, v)
    cov[2, 2] = 0.09
    s = wire.CovSummary.from_cov_ned(cov)
    assert (s.sigma_major_m, s.sigma_minor_m, s.sigma_down_m) == pytest.approx((2.0, 0.5, 0.3))
    assert s.major_azimuth_rad == pytest.approx(az)
    big = wire.CovSummary.unpack(wire.CovSummary(1e3, 0.1, 0.0, 1.0).pack(), 0)
    assert big.sigma_major_m == 65.535  # saturated, not wrapped
    # or refused, as the mission sends: a saturated sigma understates the error
    with pytest.raises(ValueError, match="sigma_major_m = 1000.0 is outside the encodable range"):
        wire.CovSummary(1e3, 0.1, 0.0, 1.0).pack(saturate=False)
    assert wire.CovSummary(65.535, 0.1, 0.0, 1.0).pack(saturate=False) == wire.CovSummary(65.535, 0.1, 0.0, 1.0).pack()
    far_fix = UsblFixReport(1, 1.6e9, 44.0, 9.8, 900.0, np.diag([150.0**2, 20.0**2, 9.0]), 44.0, 9.8)
    assert decode(far_fix.encode()).cov_ned[0, 0] == pytest.approx(65.535**2)
    with pytest.raises(ValueError, match="sigma_major_m = 150.0"):
        far_fix.encode(saturate=False)


def test_truncated_and_corrupt_packets_raise_value_error():
    rng = np.random.default_rng(3)
    packet = _random_detection(rng).encode()
    for n in range(len(packet)):
        with pytest.raises(ValueError, match="acoustic message"):
            decode(packet[:n])
    for i in range(len(packet) * 8):  # every single-bit error
        bad = bytearray(packet)
        bad[i // 8] ^= 1 << (i % 8)
        with pytest.raises(ValueError, match="CRC-16 mismatch"):
            decode(bytes(bad))
    with pytest.raises(ValueError, match="expected 33"):  # a valid CRC on a padded body
        body = packet[:-2] + b"\x00"
        decode(body + binascii.crc_hqx(body, 0xFFFF).to_bytes(2, "big"))
    with pytest.raises(ValueError, match=r"version 1\): 33 bytes, expected 32"):  # a version-2 body labelled 1
        body = b"\x01" + packet[1:-2]
        decode(body + binascii.crc_hqx(body, 0xFFFF).to_bytes(2, "big"))
    with pytest.raises(ValueError, match="protocol version 3"):
        body = b"\x03" + packet[1:-2]
        decode(body + binascii.crc_hqx(body, 0xFFFF).to_bytes(2, "big"))
    with pytest.raises(ValueError, match="unknown type 9"):
        body = b"\x02\x09" + packet[2:-2]
        decode(body + binascii.crc_hqx(body, 0xFFFF).to_bytes(2, "big"))


def test_encode_rejects_values_out_of_range():
    m = DetectionReport(1, 1.6e9, 44.0, 9.8, 5.0, np.eye(3), 0, 0.5, 0.5)
    for field, value, match in [("depth_m", 83_886.08, "depth_m = 83886.08"), ("detection_id", 70000, "message id"),
                                ("reliability", 1.5, "reliability"), ("lat_deg", float("nan"), "lat_deg"),
                                ("cov_ned", np.ones((2, 2)), "cov_ned"), ("class_id", 256, "class_id"),
                                ("t_unix_s", -1.0, "t_unix_s")]:
        kwargs = {f: getattr(m, f) for f in DetectionReport.__dataclass_fields__} | {field: value}
        with pytest.raises(ValueError, match=match):
            DetectionReport(**kwargs).encode()
    with pytest.raises(ValueError, match=r"depth_m = 400.0 is outside the encodable range \[-327.68, 327.67\]"):
        DetectionReport(1, 1.6e9, 44.0, 9.8, 400.0, np.eye(3), 0, 0.5, 0.5).encode(1)
    with pytest.raises(ValueError, match="protocol version 3"):
        DetectionReport(1, 1.6e9, 44.0, 9.8, 4.0, np.eye(3), 0, 0.5, 0.5).encode(3)


def _v1_packet(msg_type, msg_id, t_s, t_ms, lat_e7, lon_e7, depth_cm, cov_fields, tail):
    """A version-1 packet from its byte table (i16 cm depth at byte 18), CRC-16/CCITT-FALSE."""
    body = struct.pack(">BBHIHiih", 1, msg_type, msg_id, t_s, t_ms, lat_e7, lon_e7, depth_cm)
    body += struct.pack(">HHHB", *cov_fields) + tail
    return body + struct.pack(">H", binascii.crc_hqx(body, 0xFFFF))


def test_version_1_packets_still_decode():
    det = _v1_packet(1, 517, 1_688_169_700, 250, 440_935_123, 98_600_456, -1234, (1500, 400, 300, 64),
                     struct.pack(">BBB", 3, 255, 204))
    assert len(det) == 32
    d = decode(det)
    assert isinstance(d, DetectionReport) and (d.detection_id, d.class_id) == (517, 3)
    assert d.t_unix_s == pytest.approx(1_688_169_700.25)
    assert (d.lat_deg, d.lon_deg, d.depth_m) == pytest.approx((44.0935123, 9.8600456, -12.34))
    assert (d.class_prob, d.reliability) == pytest.approx((1.0, 0.8))
    s = wire.CovSummary.from_cov_ned(d.cov_ned)
    assert (s.sigma_major_m, s.sigma_minor_m, s.sigma_down_m) == pytest.approx((1.5, 0.4, 0.3))
    assert s.major_azimuth_rad == pytest.approx(64 * math.pi / 256)
    fix = _v1_packet(2, 9, 1_688_169_800, 999, -335_000_000, -1_799_999_999, 32767, (10, 10, 20, 0),
                     struct.pack(">ii", -335_000_100, -1_799_999_000))
    assert len(fix) == 37
    f = decode(fix)
    assert isinstance(f, UsblFixReport) and f.fix_id == 9 and f.depth_m == pytest.approx(327.67)
    assert (f.lat_deg, f.lon_deg, f.buoy_lat_deg, f.buoy_lon_deg) == pytest.approx(
        (-33.5, -179.9999999, -33.50001, -179.9999))
    # the encoder's version 1 is that byte table
    m = DetectionReport(517, 1_688_169_700.25, 44.0935123, 9.8600456, -12.34, d.cov_ned, 3, 1.0, 0.8)
    assert m.encode(1) == det


@pytest.mark.parametrize("depth_m", [400.0, 384.7535803959023, 6000.0, 10_994.0, -0.37])
def test_version_2_carries_full_ocean_depth(depth_m):
    origin = GeodeticOrigin()
    fix = UsblFixReport(3, 1.7e9, 44.09, 9.86, depth_m, np.diag([4.0, 4.0, 9.0]), 44.0901, 9.8601)
    packet = fix.encode()
    d = decode(packet)
    assert abs(d.depth_m - depth_m) <= DEPTH_TOL_M + EPS
    # bytes 18-20: the depth in cm, a big-endian signed 24-bit integer
    assert int.from_bytes(packet[18:21], "big", signed=True) == round(depth_m * 100)
    det = DetectionReport(4, 1.7e9, 44.09, 9.86, depth_m, np.eye(3), 1, 0.5, 0.9)
    assert abs(decode(det.encode()).depth_m - depth_m) <= DEPTH_TOL_M + EPS
    ned = d.pos_ned(origin)
    assert np.isfinite(ned).all()
    assert wire.depth_range_m(2) == (-83_886.08, 83_886.07) and wire.depth_range_m(1) == (-327.68, 327.67)


def test_schema_bounds_keep_time_and_position_fields_encodable():
    """No scenario reaches past the u32 seconds (2106) nor outside the i32 latitude and
    longitude: the schema's latest epoch plus its longest run, and the farthest corner of the
    largest patch from an origin near a pole and on the antimeridian."""
    from autonomy.geodesy import ned_to_lat_lon_depth
    from scenarios.config.comms import SurfaceLinkConfig
    from scenarios.config.world import SeabedConfig
    from scenarios.schema import Scenario

    epoch_max = SurfaceLinkConfig.model_fields["epoch_unix_s"].metadata
    t_max = max(m.le for m in epoch_max if hasattr(m, "le")) + max(
        m.le for m in Scenario.model_fields["duration_s"].metadata if hasattr(m, "le"))
    assert wire.unpack_time(wire.pack_time(t_max), 0) == pytest.approx(t_max)
    half = max(m.le for m in SeabedConfig.model_fields["extent_m"].metadata if hasattr(m, "le"))  # whole patch
    for lat0, lon0 in ((89.9, 180.0), (-89.9, -180.0), (0.0, 180.0)):
        origin = GeodeticOrigin(lat_deg=lat0, lon_deg=lon0)
        for n, e in ((half, half), (-half, -half), (half, -half)):
            lat, lon, _ = ned_to_lat_lon_depth([n, e, 11_000.0], origin)
            wire.pack_lat_lon(float(lat), float(lon))  # raises outside the field


def test_localized_detection_through_the_message():
    origin, epoch = GeodeticOrigin(), 1_602_000_000.0
    cov = np.diag([0.3, 0.2, 0.05])
    det = LocalizedDetection(123.456, np.array([10.0, 25.0, 4.0]), cov, 0.87, "opi")
    msg = DetectionReport.from_localized(det, 7, origin, epoch, ("opi", "tyre"))
    back = decode(msg.encode()).to_localized(origin, epoch, ("opi", "tyre"))
    assert back.class_name == "opi" and back.t_s == pytest.approx(123.456, abs=T_TOL_S + 1e-6)
    assert np.allclose(back.pos_ned, det.pos_ned, atol=0.0075)
    assert back.class_score == pytest.approx(0.87, abs=P_TOL)
    assert np.allclose(back.cov_ned, cov, atol=1e-3)
    with pytest.raises(ValueError, match="class 'opi' is not in the message class table"):
        DetectionReport.from_localized(det, 7, origin, epoch, ("tyre",))
