"""Build the navigation sensor suite (IMU, DVL, depth, altimeter, GPS) in one call."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from scenarios.config.nav_sensors import AltimeterConfig, DepthConfig, DvlConfig, GpsConfig, ImuConfig
from sim.rng import component_rng
from sim.sensors.base import Sensor
from sim.sensors.registry import build_sensor

NAV_SENSOR_NAMES = ("imu", "dvl", "depth", "altimeter", "gps")


class NavSensorsConfig(Protocol):
    """What :func:`build_nav_sensors` reads (``scenarios.schema.SensorsConfig`` fits)."""

    imu: ImuConfig
    dvl: DvlConfig
    depth: DepthConfig
    altimeter: AltimeterConfig
    gps: GpsConfig


def build_nav_sensors(sensors_cfg: NavSensorsConfig, mounts: dict[str, np.ndarray], seed: int) -> dict[str, Sensor]:
    """All navigation sensors keyed by name, each with its own ``component_rng(seed, name)``.

    Args:
        sensors_cfg: object with ``imu``, ``dvl``, ``depth``, ``altimeter``, ``gps`` configs.
        mounts: FRD offsets (3,) in metres of each sensor from the body origin, keyed by
            the names in :data:`NAV_SENSOR_NAMES`.
        seed: root scenario seed.
    """
    missing = [name for name in NAV_SENSOR_NAMES if name not in mounts]
    if missing:
        raise ValueError(f"build_nav_sensors: mounts lacks {missing}; required keys: {list(NAV_SENSOR_NAMES)}")
    sensors: dict[str, Sensor] = {}
    for name in NAV_SENSOR_NAMES:
        mount = np.asarray(mounts[name], dtype=float)
        if mount.shape != (3,) or not np.all(np.isfinite(mount)):
            raise ValueError(f"build_nav_sensors: mounts['{name}'] must be 3 finite FRD metres, got {mounts[name]!r}")
        sensors[name] = build_sensor(name, getattr(sensors_cfg, name), mount, component_rng(seed, name))
    return sensors


def benchmark_nav_suite(duration_s: float = 120.0, seed: int = 0) -> dict[str, float]:
    """Time the sensors and the navigation EKF on a level turning run over a flat seabed
    (analytic caster), all at their default rates. Returns per-call costs in microseconds
    and the simulated-to-wall time ratio of the navigation stack alone."""
    import time

    from autonomy.frames import rot_from_euler
    from autonomy.navigation import NavigationFilter
    from autonomy.navigation.config import NavigationConfig
    from scenarios.schema import SensorsConfig
    from sim.sensors.analytic_caster import AnalyticCaster
    from sim.sensors.base import SceneView
    from sim.sensors.nav_noise import nav_noise_model
    from sim.dynamics.truth import VehicleTruth

    cfg = SensorsConfig()
    mounts = {k: np.zeros(3) for k in NAV_SENSOR_NAMES}
    sensors = build_nav_sensors(cfg, mounts, seed)
    caster = AnalyticCaster(seabed_depth_m=6.0)
    nav = NavigationFilter(NavigationConfig(), np.array([0.0, 0.0, 2.0]), 0.0,
                           nav_noise_model(cfg.imu, cfg.dvl, cfg.depth, cfg.gps, altimeter=cfg.altimeter), mounts=mounts)
    handlers = nav.message_handlers()
    sensor_s = dict.fromkeys(NAV_SENSOR_NAMES, 0.0)
    filter_s = dict.fromkeys(NAV_SENSOR_NAMES, 0.0)
    calls = dict.fromkeys(NAV_SENSOR_NAMES, 0)
    dt = 1.0 / cfg.imu.rate_hz
    speed, yaw_rate = 0.5, 0.02
    wall0 = time.perf_counter()
    for k in range(int(duration_s / dt)):
        t = k * dt
        yaw = yaw_rate * t
        pos = np.array([speed / yaw_rate * np.sin(yaw), speed / yaw_rate * (1 - np.cos(yaw)), 2.0])
        truth = VehicleTruth(t_s=t, pos_ned=pos, R_nb=rot_from_euler(0.0, 0.0, yaw), rpy_rad=np.array([0.0, 0.0, yaw]),
                             nu=np.array([speed, 0.0, 0.0, 0.0, 0.0, yaw_rate]), nu_dot=np.zeros(6),
                             current_ned=np.zeros(3))
        for name, sensor in sensors.items():
            if k % max(1, round(cfg.imu.rate_hz / sensor.rate_hz)):
                continue
            t0 = time.perf_counter()
            msg = sensor.measure(truth, SceneView(t, caster))
            t1 = time.perf_counter()
            handlers[type(msg)](msg)
            sensor_s[name] += t1 - t0
            filter_s[name] += time.perf_counter() - t1
            calls[name] += 1
    wall = time.perf_counter() - wall0
    est = nav.estimate()
    out: dict[str, float] = {"sim_time_s": float(duration_s), "wall_time_s": wall,
                             "real_time_factor": duration_s / wall,
                             "final_position_error_m": float(np.linalg.norm(est.pos_ned - pos))}
    for name in NAV_SENSOR_NAMES:
        out[f"{name}_measure_us"] = 1e6 * sensor_s[name] / max(calls[name], 1)
        out[f"{name}_filter_us"] = 1e6 * filter_s[name] / max(calls[name], 1)
    return out
