"""Sensor classes by kind, and building a scenario's sensors from its sensor table.

A sensor class registers with ``@register_sensor(ConfigClass)``; the config class carries the
kind (``scenarios.config.sensor``). Modules of :mod:`sim.sensors` are imported on the first
lookup, so a new sensor needs no entry anywhere else.
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

S = TypeVar("S", bound=type[Sensor])

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
    global _DISCOVERED
    if _DISCOVERED:
        return
    _DISCOVERED = True
    import sim.sensors as pkg

    for info in pkgutil.walk_packages(pkg.__path__, prefix=f"{pkg.__name__}."):
        importlib.import_module(info.name)


def sensor_classes() -> dict[str, type[Sensor]]:
    """Registered kind -> sensor class."""
    _discover()
    return dict(_SENSORS)


def sensor_class(kind: str) -> type[Sensor]:
    """The class of ``kind``. Raises ``KeyError`` listing the known kinds."""
    classes = sensor_classes()
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
