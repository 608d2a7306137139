"""Sensors fire at their own times on the physics clock: at their configured rate even when
faster than the physics step (the true state moved to each stamp), first at t = 0; the
tracker takes the first USBL fix; rates the loop cannot honour are refused at load."""

from __future__ import annotations

import math
import os

from sim.events.records import ObserverBase
import numpy as np
import pytest
from scipy.linalg import expm

from autonomy.frames import rot_from_euler, skew, wrap_angle
from autonomy.messages import ImuMsg
from scenarios import ScenarioError, load_scenario
from sim.cli import main
from sim.features import TrackingFeature
from sim.mission import Mission
from sim.dynamics.truth import VehicleTruth, interpolate_truth

SCENARIOS = os.path.join(os.path.dirname(__file__), "..", "..", "..", "scenarios")
NO_IMU_NOISE = [f"sensors.imu.{k}=0" for k in (
    "roll_pitch_noise_deg", "roll_pitch_bias_deg", "fog_heading_noise_deg", "fog_heading_bias_deg",
    "fog_heading_random_walk_deg_per_sqrt_h", "ahrs_heading_noise_deg", "ahrs_heading_bias_deg", "gyro_noise_dps",
    "gyro_bias_dps", "accel_noise_mps2", "accel_bias_mps2")]


class _Messages(ObserverBase):
    sonar_truth = False
    sonar_frames = False

    def __init__(self, name: str) -> None:
        self.name, self.msgs = name, []

    def on_start(self, info) -> None:
        pass

    def on_step(self, rec) -> None:
        pass

    def on_end(self, summary) -> None:
        pass

    def on_message(self, name, msg) -> None:
        if name == self.name:
            self.msgs.append(msg)


def _truth(t, pos, R, nu, nu_dot):
    return VehicleTruth(float(t), np.asarray(pos, float), R, np.array(rot_to_rpy(R)), np.asarray(nu, float),
                        np.asarray(nu_dot, float), np.zeros(3))


def rot_to_rpy(R):
    return (math.atan2(R[2, 1], R[2, 2]), -math.asin(R[2, 0]), math.atan2(R[1, 0], R[0, 0]))


def test_interpolated_truth_is_exact_for_constant_acceleration_and_constant_body_rate():
    # straight line, constant body acceleration: position quadratic, velocity linear
    R0 = rot_from_euler(0.1, -0.05, 0.7)
    v0, acc = np.array([0.8, -0.1, 0.05]), np.array([0.3, 0.1, -0.2])

    def straight(t):
        return _truth(t, [1.0, 2.0, 3.0] + R0 @ (v0 * t + 0.5 * acc * t * t), R0, [*(v0 + acc * t), 0, 0, 0],
                      [*acc, 0, 0, 0])

    a, b = straight(0.0), straight(0.005)
    for t in (0.001, 0.0025, 0.0049):
        got, want = interpolate_truth(a, b, t), straight(t)
        assert got.t_s == t
        np.testing.assert_allclose(got.pos_ned, want.pos_ned, rtol=0, atol=1e-12)
        np.testing.assert_allclose(got.nu, want.nu, rtol=0, atol=1e-12)
        np.testing.assert_allclose(got.nu_dot, want.nu_dot, rtol=0, atol=1e-12)
    # constant body rate about a tilted axis: R(t) = R0 expm(t [w]x)
    w = np.array([0.3, -0.2, 0.9])

    def spinning(t):
        return _truth(t, [0.0, 0.0, 5.0], R0 @ expm(t * skew(w)), [0.5, 0, 0, *w], np.zeros(6))

    a, b = spinning(0.0), spinning(0.01)
    for t in (0.002, 0.005, 0.0075):
        got, want = interpolate_truth(a, b, t), spinning(t)
        np.testing.assert_allclose(got.R_nb, want.R_nb, rtol=0, atol=1e-12)
        np.testing.assert_allclose(got.rpy_rad, want.rpy_rad, rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match="outside"):
        interpolate_truth(a, b, 0.02)


def test_imu_faster_than_physics_measures_each_stamp_at_its_own_time():
    """A 400 Hz IMU on the 200 Hz physics of a vehicle turning at a constant rate on a circle
    (the truth replaced by the analytic motion): every 2.5 ms a message, stamped n / 400 s,
    with the attitude, rate and specific force of the analytic motion at its stamp."""
    scn = load_scenario("cssn_lawnmower", ["duration_s=1", "sensors.imu.rate_hz=400", "sensors.fls=null",
                                           *NO_IMU_NOISE])
    assert scn.physics.rate_hz == 200.0
    obs = _Messages("imu")
    m = Mission(scn, observers=[obs])
    u, r, psi0, centre = 0.7, 0.4, 0.3, np.array([2.0, -1.0])

    def circle(name="auv"):
        t = m.physics.t_s
        psi = psi0 + r * t
        pos = [centre[0] + u / r * (math.sin(psi) - math.sin(psi0)),
               centre[1] - u / r * (math.cos(psi) - math.cos(psi0)), 1.5]
        return _truth(t, pos, rot_from_euler(0.0, 0.0, psi), [u, 0, 0, 0, 0, r], np.zeros(6))

    m.physics.truth = circle
    m.reset()
    while not m.done:
        m.step()
    msgs = [x for x in obs.msgs if isinstance(x, ImuMsg)]
    assert len(msgs) == 401  # 0, 2.5 ms, ..., 1 s
    stamps = np.array([x.t_s for x in msgs])
    np.testing.assert_allclose(stamps, np.arange(401) / 400.0, rtol=0, atol=1e-12)
    x_m, y_m, _ = m.sensors["imu"].mount.pos_body_m
    for msg in msgs:
        psi = psi0 + r * msg.t_s
        assert msg.rpy_rad[0] == pytest.approx(0.0, abs=1e-12) and msg.rpy_rad[1] == pytest.approx(0.0, abs=1e-12)
        assert msg.rpy_rad[2] == pytest.approx(float(wrap_angle(psi)), abs=1e-12)
        np.testing.assert_allclose(msg.rate_body_radps, [0.0, 0.0, r], rtol=0, atol=1e-12)
        # specific force at the mount: centripetal r u (and r^2 of the lever arm), minus gravity
        np.testing.assert_allclose(msg.accel_body_mps2, [-r * r * x_m, r * u - r * r * y_m, -9.81], rtol=0,
                                   atol=1e-9)


def test_sensors_first_fire_at_t0_and_their_first_interval_is_the_period():
    obs = _Messages("imu")
    m = Mission(load_scenario("cssn_lawnmower", ["duration_s=0.2", "sensors.fls=null"]), observers=[obs])
    m.reset()
    while not m.done:
        m.step()
    stamps = [x.t_s for x in obs.msgs]
    np.testing.assert_allclose(stamps, np.arange(11) / 50.0, rtol=0, atol=1e-12)  # 50 Hz from t = 0
    assert m.summary().messages_delivered["dvl"] == 2  # 5 Hz: t = 0 and 0.2 s


def test_tracker_takes_the_first_usbl_fix():
    scn = load_scenario(os.path.join(SCENARIOS, "track_static_vehicle.yaml"), ["duration_s=1.5"])
    m = Mission(scn)
    m.reset()
    while not m.done:
        m.step()
    for mode in ("usbl", "fused"):
        tracker = m.feature(TrackingFeature).stack.trackers[mode]
        assert tracker.rejected == []
        assert tracker.used_counts()["usbl"] == 1  # the fix measured at t = 0


@pytest.mark.parametrize(("override", "key"), [
    ("autonomy.rate_hz=30", "autonomy.rate_hz"),
    ("autonomy.rate_hz=150", "autonomy.rate_hz"),
])
def test_rates_the_loop_cannot_honour_are_refused_at_load(override, key, capsys):
    with pytest.raises(ScenarioError, match=key.replace(".", r"\.")):
        load_scenario("cssn_lawnmower", [override])
    assert main(["validate", "cssn_lawnmower", "--set", override]) == 2
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err and len(err.splitlines()) == 1 and key in err and override in err


def test_an_extra_vehicle_sensor_faster_than_the_autonomy_tick_is_refused():
    with pytest.raises(ScenarioError, match=r"vehicles\.buoy\.compass\.rate_hz: 50 Hz exceeds autonomy\.rate_hz"):
        load_scenario("cssn_sea_trial", ["vehicles.buoy.compass.rate_hz=50"])
    load_scenario("cssn_sea_trial", ["vehicles.buoy.compass.rate_hz=10"])
