"""Sensor classes by kind, and building a scenario's sensors from its sensor table.

A sensor class registers with ``@register_sensor(ConfigClass)``; the config class carries the
kind (``scenarios.config.sensor``). Lookups are lazy: :data:`BUILTIN_SENSORS` says, kind by
kind, which module defines each built-in sensor, and a lookup imports that module only, so
a process that builds its navigation sensors never imports the sonars (nor numba, which
their compiled kernels need). A kind found neither registered nor in the table makes the
registry import every module of :mod:`sim.sensors` once (a sensor module not yet listed
still works; ``tests/sim/sensors/test_sensor_contract.py`` checks the table is complete).
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable, Mapping
from typing import TypeVar

import numpy as np
from numpy.typing import ArrayLike

from scenarios.config.sensor import SensorConfig
from sim.rng import component_rng
from sim.sensors.base import Mount, Sensor
import sim.sensors as pkg

S = TypeVar("S", bound=type[Sensor])

BUILTIN_SENSORS: dict[str, str] = {
    "imu": "sim.sensors.imu:ImuSensor",
    "dvl": "sim.sensors.dvl:DvlSensor",
    "depth": "sim.sensors.depth:DepthSensor",
    "altimeter": "sim.sensors.altimeter:AltimeterSensor",
    "gps": "sim.sensors.gps:GpsSensor",
    "usbl": "sim.sensors.usbl:UsblSensor",
    "fls": "sim.sensors.fls:FlsSensor",
    "msis": "sim.sensors.msis:MsisSensor",
    "sss": "sim.sensors.sss:SssSensor",
}
"""Kind -> ``"module:Class"`` of every sensor shipped in :mod:`sim.sensors` (imported on lookup)."""

_SENSORS: dict[str, type[Sensor]] = {}
_DISCOVERED = False


def register_sensor(config_type: type[SensorConfig]) -> Callable[[S], S]:
    """Class decorator: register a :class:`Sensor` subclass for ``config_type``'s kind.

    Raises:
        TypeError: the kind is already taken by another class.
    """
    kind = config_type.model_fields["kind"].default

    def deco(cls: S) -> S:
        other = _SENSORS.get(kind)
        if other is not None and other.__qualname__ != cls.__qualname__:
            raise TypeError(f"sensor kind {kind!r} registered twice: {other.__name__} and {cls.__name__}")
        cls.kind = kind
        cls.config_type = config_type
        _SENSORS[kind] = cls
        return cls

    return deco


def _discover() -> None:
    """Import every module of :mod:`sim.sensors` (once): each registers its sensors."""
    global _DISCOVERED
    if _DISCOVERED:
        return
    _DISCOVERED = True

    for info in pkgutil.walk_packages(pkg.__path__, prefix=f"{pkg.__name__}."):
        importlib.import_module(info.name)


def _load_builtin(kind: str) -> type[Sensor] | None:
    """Import the module :data:`BUILTIN_SENSORS` names for ``kind``; its class (None: not listed).

    Raises:
        TypeError: the module did not register that class for ``kind`` (a stale table entry).
    """
    where = BUILTIN_SENSORS.get(kind)
    if where is None:
        return None
    module, _, name = where.partition(":")
    cls = getattr(importlib.import_module(module), name)
    if _SENSORS.get(kind) is not cls:
        raise TypeError(f"sim.sensors.registry.BUILTIN_SENSORS[{kind!r}] = {where!r}, but that class is not "
                        f"the one registered for {kind!r}")
    return cls


def sensor_classes() -> dict[str, type[Sensor]]:
    """Registered kind -> sensor class (every module of :mod:`sim.sensors` imported: the
    sonars too; to build one kind, :func:`sensor_class` imports its module alone)."""
    _discover()
    return dict(_SENSORS)


def sensor_class(kind: str) -> type[Sensor]:
    """The class of ``kind``, importing only the module that defines it when it is a built-in
    kind. Raises ``KeyError`` listing the known kinds."""
    cls = _SENSORS.get(kind) or _load_builtin(kind)
    if cls is not None:
        return cls
    classes = sensor_classes()  # not listed: perhaps a module of sim.sensors not in the table
    try:
        return classes[kind]
    except KeyError:
        raise KeyError(f"no sensor of kind {kind!r}; known: {sorted(classes)}") from None


def build_sensor(name: str, cfg: SensorConfig, mount: Mount | ArrayLike, rng: np.random.Generator) -> Sensor:
    """One sensor of ``cfg.kind`` named ``name``."""
    return sensor_class(cfg.kind).from_config(name, cfg, mount, rng)


def build_sensors(table: Mapping[str, SensorConfig], site_pos_body: Callable[[str], ArrayLike] | None,
                  seed: int) -> dict[str, Sensor]:
    """The enabled entries of a sensor table, in table order, each mounted from its config
    and given its own ``component_rng(seed, name)``.

    Raises:
        ValueError: a mount site is unknown.
    """
    out: dict[str, Sensor] = {}
    for name, cfg in table.items():
        if not cfg.enabled:
            continue
        out[name] = build_sensor(name, cfg, Mount.from_config(name, cfg, site_pos_body), component_rng(seed, name))
    return out
