"""Altitude over sloping seabeds: DVL and altimeter geometry, fusion in the navigation filter,
and closed-loop altitude holding, all against the analytic distance to the seabed plane."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from autonomy.control.setpoint import Setpoint
from autonomy.frames import rot_from_euler
from autonomy.messages import ImuMsg
from autonomy.navigation import NavigationFilter
from scenarios import load_scenario
from scenarios.config.nav_sensors import AltimeterConfig, DvlConfig
from autonomy.navigation.config import NavigationConfig
from sim.mission import Mission
from sim.sensors.nav_noise import nav_noise_model
from sim.sensors.base import SceneView
from sim.sensors.altimeter import AltimeterSensor
from sim.sensors.dvl import DvlSensor
from sim.dynamics.truth import VehicleTruth
from tests.support import PlaneCaster

MOUNTS = {"dvl": np.array([0.15, -0.05, 0.25]), "altimeter": np.array([0.2, 0.05, 0.25])}


def _seabed_normal(slope_rad: float, downhill_azimuth_rad: float) -> np.ndarray:
    """Unit normal (3,), NED, facing up out of a plane whose depth grows by tan(slope) per metre
    towards ``downhill_azimuth_rad`` (from north towards east)."""
    t = math.tan(slope_rad)
    n = np.array([t * math.cos(downhill_azimuth_rad), t * math.sin(downhill_azimuth_rad), -1.0])
    return n / np.linalg.norm(n)


def _vertical_distance_m(point_ned: np.ndarray, plane_point_ned: np.ndarray, normal_ned: np.ndarray) -> float:
    """Distance (m) from ``point_ned`` straight down (NED +z) to the plane."""
    return float(normal_ned @ (plane_point_ned - point_ned) / normal_ned[2])


def _truth(t_s: float, pos_ned, rpy_rad, vel_ned_mps=(0.0, 0.0, 0.0)) -> VehicleTruth:
    rpy = np.asarray(rpy_rad, float)
    R = rot_from_euler(*rpy)
    nu = np.r_[R.T @ np.asarray(vel_ned_mps, float), np.zeros(3)]
    return VehicleTruth(t_s=t_s, pos_ned=np.asarray(pos_ned, float), R_nb=R, rpy_rad=rpy, nu=nu,
                        nu_dot=np.zeros(6), current_ned=np.zeros(3))


# ----------------------------------------------------------------------------- sensors


@pytest.mark.parametrize("slope_deg", [0.0, 5.0, 10.0, 20.0, 30.0])
@pytest.mark.parametrize("rpy_deg", [(0.0, 0.0, 0.0), (4.0, -3.0, 37.0), (-8.0, 6.0, 200.0)])
def test_dvl_altitude_is_the_vertical_distance_under_the_transducer(slope_deg, rpy_deg):
    dvl = DvlSensor(DvlConfig(max_slope_deg=40.0), MOUNTS["dvl"], np.random.default_rng(0))
    plane_point = np.array([3.0, -2.0, 14.0])
    for azimuth_deg in (0.0, 70.0, 215.0):
        normal = _seabed_normal(math.radians(slope_deg), math.radians(azimuth_deg))
        truth = _truth(0.0, [1.0, 2.0, 5.0], np.radians(rpy_deg))
        msg = dvl.measure(truth, SceneView(truth.t_s, PlaneCaster(plane_point, normal)), noise=False)
        expected = _vertical_distance_m(truth.point_ned(MOUNTS["dvl"]), plane_point, normal)
        assert msg.valid
        assert msg.altitude_m == pytest.approx(expected, abs=1e-3)


def test_filter_turns_a_tilted_altimeter_slant_range_into_altitude_over_a_slope():
    """One noise-free DVL ping gives the seabed gradient; a slant range taken at a tilted attitude
    then yields the body origin's vertical distance to the plane."""
    normal = _seabed_normal(math.radians(20.0), math.radians(120.0))
    plane_point = np.array([0.0, 0.0, 11.0])
    caster = PlaneCaster(plane_point, normal)
    rpy = np.radians([5.0, -7.0, 30.0])
    truth = _truth(0.0, [0.0, 0.0, 6.0], rpy)
    expected = _vertical_distance_m(truth.pos_ned, plane_point, normal)
    dvl = DvlSensor(DvlConfig(), MOUNTS["dvl"], np.random.default_rng(0))
    alt = AltimeterSensor(AltimeterConfig(), MOUNTS["altimeter"], np.random.default_rng(0))
    f = NavigationFilter(NavigationConfig(), truth.pos_ned, rpy[2], nav_noise_model(), mounts=MOUNTS)
    f.on_imu(ImuMsg(t_s=0.0, rpy_rad=rpy, rate_body_radps=np.zeros(3), accel_body_mps2=np.array([0, 0, -9.81])))
    f.on_dvl(dvl.measure(truth, SceneView(truth.t_s, caster), noise=False))
    assert f.estimate().altitude_m == pytest.approx(expected, abs=1e-3)
    # a filter that trusts the DVL altitude little: its ping (0.5 m off) gives the gradient only,
    # and the altimeter's slant range sets the altitude
    vague_dvl = dataclasses.replace(nav_noise_model(), dvl_range_noise_m=10.0)
    f2 = NavigationFilter(NavigationConfig(), truth.pos_ned, rpy[2], vague_dvl, mounts=MOUNTS)
    f2.on_imu(ImuMsg(t_s=0.0, rpy_rad=rpy, rate_body_radps=np.zeros(3), accel_body_mps2=np.array([0, 0, -9.81])))
    f2.on_dvl(dataclasses.replace(dvl.measure(truth, SceneView(truth.t_s, caster), noise=False), altitude_m=expected + 0.5))
    f2.on_altimeter(alt.measure(truth, SceneView(truth.t_s, caster), noise=False))
    assert f2.estimate().altitude_m == pytest.approx(expected, abs=1e-3)


# ----------------------------------------------------------------------------- fusion


def _contour_run(seed: int, dvl_bias_m: float, alt_bias_m: float, duration_s: float = 50.0):
    """Vehicle at 0.5 m/s along the contour of a 20 deg slope, 4 m above it, rolling and pitching
    a little; IMU at 10 Hz, DVL at 5 Hz, altimeter at 2 Hz, each with its own noise and bias.
    Returns the errors (m) of the 10 Hz estimate and of each sensor's own body-origin altitude."""
    rng = np.random.default_rng(seed)
    dvl_cfg = DvlConfig(range_noise_m=0.05)
    alt_cfg = AltimeterConfig(noise_m=0.02)
    dvl = DvlSensor(dvl_cfg, MOUNTS["dvl"], rng)
    alt = AltimeterSensor(alt_cfg, MOUNTS["altimeter"], rng)
    noise = nav_noise_model(dvl=dvl_cfg, altimeter=alt_cfg)
    normal = _seabed_normal(math.radians(20.0), math.radians(90.0))  # deeper to the east
    plane_point = np.array([0.0, 0.0, 10.0])
    caster = PlaneCaster(plane_point, normal)
    f = NavigationFilter(NavigationConfig(), [0.0, 0.0, 6.0], 0.0, noise, mounts=MOUNTS)
    est_err, dvl_err, alt_err = [], [], []
    for k in range(int(duration_s * 10) + 1):
        t = 0.1 * k
        rpy = np.array([0.03 * math.sin(0.4 * t), 0.02 * math.sin(0.3 * t + 1.0), 0.0])
        truth = _truth(t, [0.5 * t, 0.0, 6.0], rpy, [0.5, 0.0, 0.0])
        true_alt = _vertical_distance_m(truth.pos_ned, plane_point, normal)
        f.on_imu(ImuMsg(t_s=t, rpy_rad=rpy, rate_body_radps=np.zeros(3), accel_body_mps2=np.array([0, 0, -9.81])))
        R = truth.R_nb
        if k % 2 == 0:
            msg = dvl.measure(truth, SceneView(truth.t_s, caster))
            msg = dataclasses.replace(msg, altitude_m=msg.altitude_m + dvl_bias_m)
            f.on_dvl(msg)
            if msg.valid:
                mount = truth.point_ned(MOUNTS["dvl"])
                dvl_err.append(_origin_altitude_m(truth, mount, mount[2] + msg.altitude_m) - true_alt)
        if k % 5 == 0:
            msg = alt.measure(truth, SceneView(truth.t_s, caster))
            msg = dataclasses.replace(msg, altitude_m=msg.altitude_m + alt_bias_m)
            f.on_altimeter(msg)
            if msg.valid:
                mount = truth.point_ned(MOUNTS["altimeter"])
                echo = mount + msg.altitude_m * truth.R_nb[:, 2]
                alt_err.append(_origin_altitude_m(truth, echo, echo[2]) - true_alt)
        f.predict(t)
        est_err.append(f.estimate().altitude_m - true_alt)
    return np.array(est_err), np.array(dvl_err), np.array(alt_err)


def _origin_altitude_m(truth: VehicleTruth, point_ned: np.ndarray, seabed_depth_m: float) -> float:
    """Body-origin altitude (m) implied by a seabed depth ``seabed_depth_m`` measured under
    ``point_ned``, carried to the origin along the true 20 deg plane of :func:`_contour_run`."""
    east_offset_m = truth.pos_ned[1] - point_ned[1]
    return seabed_depth_m + math.tan(math.radians(20.0)) * east_offset_m - truth.pos_ned[2]



def test_fused_altitude_has_no_sawtooth_and_beats_each_sensor():
    dvl_sigma = 0.05 * math.cos(math.radians(30.0)) / 2.0  # 4 beams, vertical part of 5 cm range noise
    alt_sigma = 0.02 + 0.002 * 4.0
    fused_sigma = (dvl_sigma**-2 + alt_sigma**-2) ** -0.5
    for seed, dvl_bias, alt_bias in [(1, 0.01, -0.01), (2, -0.008, 0.012), (3, 0.005, 0.005)]:
        est_err, dvl_err, alt_err = _contour_run(seed, dvl_bias, alt_bias)
        settled = est_err[50:]  # after 5 s
        jumps = np.abs(np.diff(settled))
        assert jumps.max() < 2.0 * fused_sigma, (seed, jumps.max())
        rms = lambda e: float(np.sqrt(np.mean(e**2)))  # noqa: E731
        assert rms(settled) < min(rms(dvl_err), rms(alt_err)), (seed, rms(settled), rms(dvl_err), rms(alt_err))
        assert abs(settled.mean()) < max(abs(dvl_err.mean()), abs(alt_err.mean())) + 0.003


# ----------------------------------------------------------------------------- closed loop


def test_closed_loop_holds_altitude_along_a_slope():
    """Contour-following at 4 m over a 20 deg slope with the altimeter at 2 Hz and the DVL at 5 Hz."""
    overrides = ["autonomy.atr.detector=classical", "sensors.fls.enabled=false", "world.seabed.kind=slope",
                 "world.seabed.slope_deg=20", "world.seabed.slope_azimuth_deg=90", "world.seabed.depth_m=10",
                 "vehicle.initial_pos_ned=[-25.0,17.0,6.0]", "vehicle.initial_rpy_deg=[0,0,0]",
                 "sensors.altimeter.rate_hz=2", "sensors.dvl.rate_hz=5",
                 "autonomy.guidance.mission.safe_depth_max_m=30"]  # the slope's deep end (the test steers itself)
    scn = load_scenario("cssn_lawnmower", overrides)
    seabed = scn.world.seabed
    normal = _seabed_normal(math.radians(seabed.slope_deg), math.radians(seabed.slope_azimuth_deg))
    plane_point = np.array([seabed.center_ne_m[0], seabed.center_ne_m[1], seabed.depth_m])
    mission = Mission(scn)
    mission.reset(0)
    altitudes = []
    for _ in range(600):
        rec = mission.step(Setpoint(0.5, 0.0, altitude_m=4.0))
        if rec.t_s > 20.0:
            altitudes.append(_vertical_distance_m(rec.truth.pos_ned, plane_point, normal))
    assert abs(np.mean(altitudes) - 4.0) < 0.02
