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
