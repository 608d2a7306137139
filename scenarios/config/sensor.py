"""What every sensor config holds, the registry of sensor kinds, and the scenario's sensor table.

A sensor config class declares its ``kind`` as a one-value ``Literal`` and registers with
:func:`sensor_config`. The scenario's ``sensors:`` section is a table of named entries, each
validated as the config class of its ``kind`` (a pydantic discriminated union built from the
registry, so no list of kinds is kept by hand). An entry's ``kind`` defaults to its name, so
``sensors: {fls: {...}, dvl: {...}}`` needs no ``kind``; a second sonar is
``sensors: {fls_port: {kind: fls, mount_site: ...}}``.

Config modules are found by importing every module of :mod:`scenarios.config` once (a new
sensor's config module needs no registration elsewhere).
"""

from __future__ import annotations

import importlib
import pkgutil
from typing import Any

from pydantic import Field

from scenarios.config.base import StrictModel, Vec3
import scenarios.config as pkg

#: Entries (name = kind) every scenario gets unless its ``sensors:`` section sets them to
#: ``null``: the navigation suite and the forward-looking sonar, in the order they fire.
DEFAULT_ENTRIES: tuple[str, ...] = ("imu", "dvl", "depth", "altimeter", "gps", "fls")

_KINDS: dict[str, type["SensorConfig"]] = {}
_DISCOVERED = False


class SensorConfig(StrictModel):
    """Fields shared by every sensor.

    Attributes:
        kind: the sensor type; selects the config class and the simulated sensor.
        enabled: False keeps the entry but builds no sensor.
        rate_hz: sampling rate, Hz (the scheduler fires the sensor at this rate).
        latency_s: fixed delay from sampling to delivery, s (a sensor may add a
            message-dependent part, e.g. acoustic travel time).
        mount_site: hull site the sensor sits at (None: the site named like the entry).
        mount_pos_body_m: (3,) FRD offset from the body origin, m; replaces the site position.
        mount_rpy_deg: (3,) roll, pitch, yaw of the sensor frame w.r.t. the body (FRD), deg.
    """

    kind: str
    enabled: bool = True
    rate_hz: float = Field(1.0, gt=0.0)
    latency_s: float = Field(0.0, ge=0.0, le=5.0, description="delay from sampling to delivery, s")
    mount_site: str | None = Field(None, min_length=1, description="hull site; None: the entry's name")
    mount_pos_body_m: Vec3 | None = Field(None, description="FRD offset, m; overrides the site's position")
    mount_rpy_deg: Vec3 = Field((0.0, 0.0, 0.0), description="sensor frame w.r.t. body: roll, pitch, yaw, deg")


def sensor_config(cls: type[SensorConfig]) -> type[SensorConfig]:
    """Class decorator: register a sensor config class under its ``kind`` literal.

    Raises:
        TypeError: ``kind`` has no string default, or another class holds that kind.
    """
    kind = cls.model_fields["kind"].default
    if not isinstance(kind, str) or not kind:
        raise TypeError(f"{cls.__name__}: declare `kind: Literal['<kind>'] = '<kind>'`")
    other = _KINDS.get(kind)
    if other is not None and other.__qualname__ != cls.__qualname__:
        raise TypeError(f"sensor kind {kind!r} registered twice: {other.__name__} and {cls.__name__}")
    _KINDS[kind] = cls
    return cls


def _discover() -> None:
    global _DISCOVERED
    if _DISCOVERED:
        return
    _DISCOVERED = True

    for info in pkgutil.iter_modules(pkg.__path__):
        importlib.import_module(f"{pkg.__name__}.{info.name}")


def sensor_config_kinds() -> dict[str, type[SensorConfig]]:
    """Registered kind -> config class, in registration order."""
    _discover()
    return dict(_KINDS)


def fill_sensor_entries(data: Any) -> Any:
    """Raw ``sensors:`` mapping -> mapping ready for the union: :data:`DEFAULT_ENTRIES` added
    where absent (first, in their order; then the scenario's other entries in file order),
    ``kind`` set from the name where absent, and entries set to ``null`` removed (a scenario
    without that sensor)."""
    if data is None:
        data = {}
    if not isinstance(data, dict):
        return data  # let pydantic report the type error
    kinds = sensor_config_kinds()
    out: dict[str, Any] = {}
    for name in DEFAULT_ENTRIES:
        if name not in data:
            out[name] = {"kind": name}
    for name, entry in data.items():
        if entry is None:
            out.pop(name, None)
            continue
        if isinstance(entry, dict) and "kind" not in entry and name in kinds:
            entry = {**entry, "kind": name}
        elif isinstance(entry, SensorConfig):
            entry = entry.model_dump()
        out[name] = entry
    # keep the default entries' order, then the scenario's extra entries in file order
    order = [n for n in DEFAULT_ENTRIES if n in out] + [n for n in data if n in out and n not in DEFAULT_ENTRIES]
    return {n: out[n] for n in order}

