"""Every registered sensor honours the one sensor contract.

Parametrised over the registry: each kind builds from its default config, returns finite
values (or says it is invalid) on the analytic caster, repeats itself bit for bit for a seed,
is exactly noise-free when asked (checked against values computed here from the truth, not
by the sensor's code), and is fired by the scheduler at its rate and delivered after its
latency. A test-only acoustic ranging sensor, registered here, checks a latency that
depends on the message (two-way travel time).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Literal

import numpy as np
import pytest
from pydantic import Field

from autonomy.frames import wrap_angle
from scenarios.config.sensor import SensorConfig, sensor_config, sensor_config_kinds
from scenarios.schema import SensorsConfig
from sim.rng import component_rng
from sim.scheduler import SensorScheduler
from sim.sensors.analytic_caster import AnalyticCaster, AnalyticSphere
from sim.sensors.base import Mount, SceneView, Sensor
from sim.sensors.registry import build_sensor, register_sensor, sensor_classes
from sim.truth import VehicleTruth
from tests.autonomy.navigation.test_kinematics import static_truth, wiggle_truth

SEABED_DEPTH_M = 6.0
MOUNT = Mount(np.array([0.3, -0.1, 0.15]))
SPHERE_CENTRE = np.array([12.0, 0.5, 5.2])


@dataclasses.dataclass(frozen=True)
class _Obj:
    id: int
    name: str
    class_name: str
    is_target: bool
    centroid_ned: np.ndarray


def _scene(t_s: float) -> SceneView:
    """Analytic scene: flat seabed and one sphere, with its object record for ground truth."""
    caster = AnalyticCaster(SEABED_DEPTH_M, spheres=(AnalyticSphere(SPHERE_CENTRE, 0.5, 0),))
    return SceneView(t_s, caster, (_Obj(0, "ball", "opi", True, SPHERE_CENTRE),))


# ----------------------------------------------------------------------------- test-only sensor
@dataclasses.dataclass(frozen=True)
class RangeMsg:
    t_s: float
    range_m: float


@sensor_config
class _RangerConfig(SensorConfig):
    kind: Literal["test_ranger"] = "test_ranger"
    rate_hz: float = Field(2.0, gt=0.0)
    latency_s: float = Field(0.01, ge=0.0)
    beacon_ned: tuple[float, float, float] = (40.0, 0.0, 0.0)
    sound_speed_mps: float = 1500.0
    noise_m: float = 0.1


@register_sensor(_RangerConfig)
class _Ranger(Sensor[RangeMsg]):
    """Range to a fixed beacon; the reply is late by its two-way travel time."""

    def ideal(self, truth: VehicleTruth, scene: SceneView) -> RangeMsg:
        rel = np.asarray(self.cfg.beacon_ned) - truth.point_ned(self.mount.pos_body_m)
        return RangeMsg(truth.t_s, float(np.linalg.norm(rel)))

    def corrupt(self, ideal: RangeMsg, truth: VehicleTruth) -> RangeMsg:
        return RangeMsg(ideal.t_s, ideal.range_m + self.cfg.noise_m * float(self._rng.standard_normal()))

    def latency_s(self, msg: RangeMsg) -> float:
        return self.cfg.latency_s + 2.0 * msg.range_m / self.cfg.sound_speed_mps


KINDS = sorted(sensor_classes())


# ----------------------------------------------------------------------------- helpers
def _flatten(msg) -> np.ndarray:
    """Every number of a message (dataclass fields, nested one level), as one float vector."""
    out = []
    for f in dataclasses.fields(msg):
        v = getattr(msg, f.name)
        if dataclasses.is_dataclass(v):
            out.append(_flatten(v))
        elif isinstance(v, (bool, int, float, np.ndarray, np.number, list, tuple)):
            try:
                out.append(np.atleast_1d(np.asarray(v, dtype=float)).ravel())
            except (TypeError, ValueError):
                continue
    return np.concatenate(out) if out else np.zeros(0)


def _make(kind: str, seed: int = 3) -> Sensor:
    cls = sensor_classes()[kind]
    return build_sensor(kind, cls.config_type(), MOUNT, component_rng(seed, kind))


def _truths() -> list[VehicleTruth]:
    """Submerged and manoeuvring, then at the surface (GPS fix), then deep and level."""
    return [wiggle_truth(t) for t in (0.0, 3.0, 7.5)] + [
        static_truth(pos_ned=(1.0, 2.0, 0.0), rpy_rad=(0.0, 0.0, 0.4), t_s=8.0),
        static_truth(pos_ned=(0.0, 0.0, 4.0), rpy_rad=(0.0, 0.0, 0.0), t_s=9.0),
    ]


# ----------------------------------------------------------------------------- registry
def test_every_scenario_kind_has_a_sensor_and_default_entries_are_typed_by_kind():
    schema_kinds = {k for k in sensor_config_kinds() if not k.startswith("test_")}
    assert schema_kinds <= set(sensor_classes())
    table = SensorsConfig({"fls_port": {"kind": "fls", "mount_pos_body_m": [0.3, -0.2, 0.1]}, "gps": None})
    assert list(table) == ["imu", "dvl", "depth", "altimeter", "fls", "fls_port"]
    assert type(table["fls_port"]) is type(table["fls"]) is sensor_classes()["fls"].config_type
    for name, cfg in table.items():
        assert type(cfg) is sensor_classes()[cfg.kind].config_type, name


# ----------------------------------------------------------------------------- contract
@pytest.mark.parametrize("kind", KINDS)
def test_builds_from_default_config_and_returns_finite_or_flagged_values(kind):
    sensor = _make(kind)
    assert sensor.kind == kind and sensor.name == kind and sensor.rate_hz > 0.0
    for truth in _truths():
        msg = sensor.measure(truth, _scene(truth.t_s))
        assert float(msg.t_s if hasattr(msg, "t_s") else msg.frame.t_s) == truth.t_s
        values = _flatten(msg)
        if getattr(msg, "valid", True):
            assert np.all(np.isfinite(values)), (kind, msg)
        else:  # invalid: says so, and carries no made-up numbers
            assert np.any(np.isnan(values))
        assert sensor.latency_s(msg) >= 0.0


@pytest.mark.parametrize("kind", KINDS)
def test_same_seed_gives_bit_identical_messages_and_noise_is_drawn(kind):
    a, b, c = _make(kind, 5), _make(kind, 5), _make(kind, 6)
    ma, mb, mc, exact = [], [], [], []
    for truth in _truths():
        scene = _scene(truth.t_s)
        ma.append(_flatten(a.measure(truth, scene)))
        mb.append(_flatten(b.measure(truth, scene)))
        mc.append(_flatten(c.measure(truth, scene)))
        exact.append(_flatten(a.measure(truth, scene, noise=False)))
    np.testing.assert_array_equal(np.concatenate(ma), np.concatenate(mb))
    # the noise stream is really used: another seed, or no noise, changes the values
    assert not np.array_equal(np.nan_to_num(np.concatenate(ma)), np.nan_to_num(np.concatenate(mc)))
    assert not np.array_equal(np.nan_to_num(np.concatenate(ma)), np.nan_to_num(np.concatenate(exact)))
    # reset with the same stream replays it
    a.reset(component_rng(5, kind))
    again = [_flatten(a.measure(t, _scene(t.t_s))) for t in _truths()]
    np.testing.assert_array_equal(np.concatenate(again), np.concatenate(ma))


def _expected(kind: str, sensor: Sensor, truth: VehicleTruth) -> dict[str, object] | None:
    """Noise-free values computed here from the truth and the scene's geometry."""
    r = sensor.mount.pos_body_m
    R = truth.R_nb
    p_mount = truth.pos_ned + R @ r
    omega = truth.nu[3:]
    if kind == "imu":
        w_cross_r = np.cross(omega, r)
        accel = (truth.nu_dot[:3] + np.cross(omega, truth.nu[:3]) + np.cross(truth.nu_dot[3:], r)
                 + np.cross(omega, w_cross_r))
        rpy = np.array(truth.rpy_rad)
        rpy[2] = wrap_angle(rpy[2])
        return {"rpy_rad": rpy, "rate_body_radps": omega,
                "accel_body_mps2": accel - R.T @ np.array([0.0, 0.0, 9.81])}
    if kind == "dvl":
        return {"valid": True, "vel_body_mps": truth.nu[:3] + np.cross(omega, r),
                "altitude_m": SEABED_DEPTH_M - p_mount[2]}
    if kind == "depth":
        return {"depth_m": p_mount[2]}
    if kind == "altimeter":
        beam_ned = R[:, 2]
        return {"valid": True, "altitude_m": (SEABED_DEPTH_M - p_mount[2]) / beam_ned[2]}
    if kind == "gps":
        surfaced = p_mount[2] <= sensor.cfg.max_antenna_depth_m
        return {"valid": bool(surfaced), "pos_ne_m": p_mount[:2] if surfaced else np.full(2, np.nan)}
    if kind == "test_ranger":
        return {"range_m": float(np.linalg.norm(np.asarray(sensor.cfg.beacon_ned) - p_mount))}
    if kind == "usbl":  # default: a beacon at the mission origin, head aligned with the body
        d = R.T @ (np.asarray(sensor.cfg.beacon_pos_ned, dtype=float) - p_mount)
        return {"range_m": float(np.sqrt(d @ d)), "bearing_rad": float(np.arctan2(d[1], d[0])),
                "elevation_rad": float(np.arcsin(d[2] / np.sqrt(d @ d))), "valid": True}
    return None


@pytest.mark.parametrize("kind", KINDS)
def test_noise_free_values_are_exact(kind):
    sensor = _make(kind)
    for truth in _truths():
        msg = sensor.measure(truth, _scene(truth.t_s), noise=False)
        if kind == "fls":
            # expected image = mean echo + noise floor; the sphere's truth sits where it is
            floor = np.float32(10.0 ** (0.1 * sensor.cfg.noise_floor_db))
            np.testing.assert_array_equal(msg.intensity, msg.mean_intensity + floor)
            head = truth.pos_ned + truth.R_nb @ sensor.mount_pos_body_m
            np.testing.assert_allclose(msg.truth.pos_ned, head, atol=1e-12)
            obj = msg.truth.object(0)
            assert obj.range_m == pytest.approx(float(np.linalg.norm(SPHERE_CENTRE - head)), abs=1e-9)
            continue
        if kind == "msis":
            # a fresh head's next angle is its start; samples are the dB display of mean + floor
            cfg = sensor.cfg
            period = round(2 * cfg.range_m / (cfg.number_of_samples * cfg.speed_of_sound_mps * 25e-9))
            dr = cfg.speed_of_sound_mps * 25e-9 * period / 2
            assert msg.ping.angle_grad == 0.0 and msg.ping.sample_period_ticks == period
            assert msg.ping.sample_spacing_m == pytest.approx(dr, rel=1e-12)
            head = truth.pos_ned + truth.R_nb @ sensor.mount_pos_body_m
            np.testing.assert_allclose(msg.truth.pos_ned, head, atol=1e-12)
            r = (np.arange(cfg.number_of_samples) + 0.5) * dr
            tvg_db = cfg.tvg_spreading_db_per_decade * np.log10(r) + 2 * cfg.absorption_db_per_m * r
            power = msg.truth.mean_intensity.astype(float) + 10 ** (0.1 * cfg.noise_floor_db)
            db = 10 * np.log10(power) + tvg_db + cfg.gain_db
            want = np.clip(np.round(255 * (db + cfg.dynamic_range_db) / cfg.dynamic_range_db), 0, 255)
            assert np.max(np.abs(msg.ping.intensity.astype(int) - want)) <= 1  # float32 rounding
            continue
        if kind == "sss":
            # expected lines = mean echo + noise floor; altitude = the body-down ray to the seabed plane
            floor = np.float32(10.0 ** (0.1 * sensor.cfg.noise_floor_db))
            np.testing.assert_array_equal(msg.intensity, msg.mean_intensity + floor)
            head = truth.pos_ned + truth.R_nb @ sensor.mount_pos_body_m
            np.testing.assert_allclose(msg.pos_ned, head, atol=1e-12)
            down = truth.R_nb[:, 2]
            assert msg.ping.altitude_m == pytest.approx((SEABED_DEPTH_M - head[2]) / down[2], abs=1e-9)
            continue
        expected = _expected(kind, sensor, truth)
        assert expected is not None, f"no independent oracle for sensor kind {kind!r}: add one here"
        for field, want in expected.items():
            got = getattr(msg, field)
            if isinstance(want, bool):
                assert got == want, (kind, field, truth.t_s)
            else:
                np.testing.assert_allclose(got, want, rtol=0.0, atol=1e-9, err_msg=f"{kind}.{field}")


@pytest.mark.parametrize("kind", KINDS)
def test_scheduler_fires_at_rate_and_delivers_after_latency(kind):
    sensor = _make(kind)
    dt = 0.005
    duration_s = 3.0 if kind == "fls" else 10.0
    sch = SensorScheduler(eps_s=0.25 * dt)
    sch.add(kind, sensor.rate_hz, sensor.latency_s)
    fired, delivered, sent = [], [], {}
    for k in range(1, int(round(duration_s / dt)) + 1):
        t = k * dt
        if sch.due(t):
            msg = sensor.measure(wiggle_truth(t), _scene(t))
            fired.append(t)
            sent[id(msg)] = (t, sensor.latency_s(msg), msg)
            sch.push(kind, t, msg)
        for _, msg in sch.pop_ready(t):
            t_fire, latency, _ = sent[id(msg)]
            delivered.append((t_fire, latency, t))
    period = 1.0 / sensor.rate_hz
    assert len(fired) == pytest.approx(duration_s * sensor.rate_hz, abs=1)
    assert np.allclose(np.diff(fired), period, atol=dt)
    assert len(delivered) >= len(fired) - math.ceil(max(lat for _, lat, _ in delivered) / period) - 1
    for t_fire, latency, t_del in delivered:
        assert t_fire + latency - 0.25 * dt <= t_del < t_fire + latency + dt


def test_range_dependent_latency_is_the_two_way_travel_time():
    sensor = _make("test_ranger")
    c = sensor.cfg.sound_speed_mps
    dt = 0.005
    sch = SensorScheduler(eps_s=0.25 * dt)
    sch.add("ranger", sensor.rate_hz, sensor.latency_s)
    arrivals = []
    for k in range(1, 4001):  # 20 s, the beacon 15 .. 45 m away
        t = k * dt
        truth = static_truth(pos_ned=(-5.0 + 1.5 * t, 3.0, 2.0), t_s=t)
        if sch.due(t):
            sch.push("ranger", t, sensor.measure(truth, None, noise=False))
        arrivals += [(msg, t) for _, msg in sch.pop_ready(t)]
    assert len(arrivals) >= 38
    lags = []
    for msg, t_del in arrivals:
        pos = np.array([-5.0 + 1.5 * msg.t_s, 3.0, 2.0]) + MOUNT.pos_body_m
        want = sensor.cfg.latency_s + 2.0 * float(np.linalg.norm(np.asarray(sensor.cfg.beacon_ned) - pos)) / c
        assert msg.t_s + want - 0.25 * dt <= t_del < msg.t_s + want + dt
        lags.append(want)
    assert max(lags) - min(lags) > 0.03  # the latency really varies with range
