"""The one typed scenario object. Every component receives only its own sub-config."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Annotated, Any, Literal, Union

from pydantic import Field, RootModel, TypeAdapter, ValidationError, field_validator, model_validator
from pydantic_core import InitErrorDetails, PydanticUndefined

from autonomy.atr.config import AtrConfig
from autonomy.control.config import ControlConfig
from autonomy.guidance.config import GuidanceConfig
from autonomy.localization.config import LocalizationConfig
from autonomy.msis.config import MsisLocalizationConfig
from autonomy.navigation.config import NavigationConfig
from autonomy.tracking.config import TrackingConfig
from autonomy.world_model.config import WorldModelConfig
from scenarios.config.base import StrictModel
from scenarios.config.comms import CommsConfig
from scenarios.config.mcm import McmConfig
from scenarios.config.outputs import OutputsConfig
from scenarios.config.sensor import SensorConfig, fill_sensor_entries, sensor_config_kinds
from scenarios.config.vehicle import SurfaceVehicleConfig, VehicleConfig
from scenarios.config.world import WorldConfig
from scenarios.fls_presets import resolve_geometry


#: Names an extra vehicle may not take: the AUV's name in ``Physics.vehicles`` and its
#: hull's attach prefix.
RESERVED_VEHICLE_NAMES = ("auv", "hull")


class PhysicsConfig(StrictModel):
    rate_hz: float = Field(200.0, ge=20.0, le=5000.0)
    integrator: Literal["euler", "implicitfast", "rk4"] = "implicitfast"
    ray_caster: Literal["mujoco", "embree"] = Field(
        "mujoco", description="what casts the sensors' rays: mujoco (mj_multiRay, float64, the same on every "
        "CPU); embree (Embree's BVH where embreex is installed and every geom the rays meet is a mesh, box or "
        "plane that stays still, else mujoco: about 2.5x faster casts, distances to about 1e-5 m; across CPUs "
        "a ray grazing an edge may land on the other side)")


def _sensor_entry_type() -> Any:
    """``Annotated[Union[<every registered sensor config>], discriminator 'kind']``."""
    classes = tuple(sensor_config_kinds().values())
    return Annotated[Union[classes], Field(discriminator="kind")]  # noqa: UP007 (runtime union of classes)


SensorEntry = _sensor_entry_type()
_SENSOR_TABLE = TypeAdapter(dict[str, SensorEntry])


class SensorsConfig(RootModel[dict[str, SensorEntry]]):  # type: ignore[valid-type]
    """The scenario's sensors: named entries, each typed by its ``kind``.

    ``kind`` defaults to the entry's name; the default suite
    (:data:`scenarios.config.sensor.DEFAULT_ENTRIES`) is added where a scenario leaves it out,
    and an entry set to ``null`` removes that sensor. Entries read as attributes or items:
    ``sensors.fls``, ``sensors["fls"]``. Validation errors point at
    ``sensors.<name>.<field>``.
    """

    model_config = {"frozen": True}

    @model_validator(mode="wrap")
    @classmethod
    def _validate_table(cls, data: Any, handler: Any) -> "SensorsConfig":
        if isinstance(data, SensorsConfig):
            return data
        if data is PydanticUndefined:  # SensorsConfig() with no argument: the default suite
            data = {}
        raw = fill_sensor_entries(data)
        try:
            table = _SENSOR_TABLE.validate_python(raw)
        except ValidationError as exc:
            raise _without_union_tags(exc) from None
        return handler(table)

    def __getattr__(self, name: str) -> SensorConfig:
        if not name.startswith("_"):
            root = self.__dict__.get("root")
            if root is not None and name in root:
                return root[name]
        return super().__getattr__(name)  # type: ignore[misc]

    def __getitem__(self, name: str) -> SensorConfig:
        return self.root[name]

    def __contains__(self, name: object) -> bool:
        return name in self.root

    def __iter__(self) -> Iterator[str]:  # type: ignore[override]
        return iter(self.root)

    def items(self) -> Iterator[tuple[str, SensorConfig]]:
        return iter(self.root.items())

    def get(self, name: str) -> SensorConfig | None:
        return self.root.get(name)

    def enabled(self) -> dict[str, SensorConfig]:
        """Entries to build, in firing order."""
        return {n: c for n, c in self.root.items() if c.enabled}

    def first_of_kind(self, kind: str) -> SensorConfig | None:
        """The first enabled entry of ``kind`` (the one the navigation filter fuses)."""
        return next((c for c in self.root.values() if c.kind == kind and c.enabled), None)


def _without_union_tags(exc: ValidationError) -> ValidationError:
    """Drop the union tag pydantic puts after the entry name (``fls.fls.rate_hz`` ->
    ``fls.rate_hz``) so errors name the scenario's own keys."""
    kinds = sensor_config_kinds()
    details: list[InitErrorDetails] = []
    for err in exc.errors():
        loc = tuple(err["loc"])
        kind = err["type"]
        if len(loc) >= 2 and loc[1] in kinds:
            loc = (loc[0], *loc[2:])
        if kind == "union_tag_not_found":  # an entry named unlike any kind, without `kind:`
            kind, loc = "missing", (*loc, "kind")
        detail: InitErrorDetails = {"type": kind, "loc": loc, "input": err["input"]}
        if "ctx" in err and kind != "missing":
            detail["ctx"] = err["ctx"]
        details.append(detail)
    return ValidationError.from_exception_data(exc.title, details)


class AutonomyConfig(StrictModel):
    """The onboard stack's settings; each block is defined next to its code in ``autonomy/``."""

    rate_hz: float = Field(10.0, gt=0.0, le=200.0)
    navigation: NavigationConfig = NavigationConfig()
    guidance: GuidanceConfig = GuidanceConfig()
    control: ControlConfig = ControlConfig()
    atr: AtrConfig = AtrConfig()
    localization: LocalizationConfig = LocalizationConfig()
    world_model: WorldModelConfig = WorldModelConfig()
    msis_localization: MsisLocalizationConfig = MsisLocalizationConfig()
    tracking: TrackingConfig = TrackingConfig()


def without_default_gps_indoors(data: Any) -> Any:
    """A raw scenario mapping with ``sensors.gps: null`` added when ``world.indoor`` is true
    and the scenario names no ``gps`` entry: indoors the default suite has no GPS. (An entry
    the scenario names itself stays, and :class:`Scenario` refuses it if enabled.) The
    loaders (:mod:`scenarios.load`) apply it before validation; other input is returned as is.
    """
    if not isinstance(data, dict):
        return data
    world = data.get("world")
    if not (isinstance(world, dict) and world.get("indoor") is True):
        return data
    sensors = data.get("sensors")
    if sensors is None:
        sensors = {}
    if isinstance(sensors, dict) and "gps" not in sensors:
        data = {**data, "sensors": {**sensors, "gps": None}}
    return data


class Scenario(StrictModel):
    """A whole simulation scenario, loaded once from YAML."""

    name: str = Field(min_length=1)
    description: str = ""
    seed: int = Field(0, ge=0, le=2**63 - 1)
    duration_s: float = Field(600.0, gt=0.0, le=86400.0)
    physics: PhysicsConfig = PhysicsConfig()
    world: WorldConfig = WorldConfig()
    vehicle: VehicleConfig = VehicleConfig()
    #: Further vehicles by name (the AUV is ``vehicle``); names ``auv`` and ``hull`` are taken.
    vehicles: dict[Annotated[str, Field(pattern=r"^[a-z][a-z0-9_]{0,31}$")], SurfaceVehicleConfig] = {}
    sensors: SensorsConfig = SensorsConfig()
    autonomy: AutonomyConfig = AutonomyConfig()
    comms: CommsConfig = Field(CommsConfig(), description="channels between vehicles (acoustic modem link)")
    outputs: OutputsConfig = OutputsConfig()
    mcm: McmConfig = Field(McmConfig(), description="mine-countermeasures mapping on side-scan tiles (mode: full)")

    @model_validator(mode="after")
    def _no_gps_indoors(self) -> "Scenario":
        if self.world.indoor:
            names = [n for n, c in self.sensors.enabled().items() if c.kind == "gps"]
            if names:
                raise ValueError(f"sensors.{names[0]}: a GPS has no fix indoors (world.indoor is true: no sky "
                                 f"view); remove it (sensors.{names[0]}: null) or set world.indoor: false")
        return self

    @field_validator("vehicles")
    @classmethod
    def _free_vehicle_names(cls, value: dict[str, SurfaceVehicleConfig]) -> dict[str, SurfaceVehicleConfig]:
        taken = sorted(set(value) & set(RESERVED_VEHICLE_NAMES))
        if taken:
            raise ValueError(f"vehicle name {taken[0]!r} is taken (the AUV is 'vehicle'; reserved: "
                             f"{', '.join(RESERVED_VEHICLE_NAMES)})")
        return value

    @model_validator(mode="after")
    def _outputs_have_their_sonar(self) -> "Scenario":
        for key, kind, what in (("xtf", "sss", "a side-scan sonar"), ("ping360_log", "msis", "a scanning sonar")):
            if getattr(self.outputs, key) and self.sensors.first_of_kind(kind) is None:
                raise ValueError(f"outputs.{key}: the scenario has no enabled sensor of kind {kind} ({what}) to "
                                 "write; set it false or add one")
        return self

    @model_validator(mode="after")
    def _inspection_has_its_world_model(self) -> "Scenario":
        auto = self.autonomy
        if not auto.guidance.inspection.enabled:
            return self
        enabled = self.sensors.enabled()
        name = auto.atr.sonar_sensor
        has_fls = (enabled.get(name) is not None and enabled[name].kind == "fls") if name is not None else any(
            c.kind == "fls" for c in enabled.values())
        if not has_fls or auto.atr.detector == "none":
            raise ValueError("autonomy.guidance.inspection.enabled: inspection reads the world model, which needs an "
                             "enabled forward-looking sonar (kind fls) and a detector (autonomy.atr.detector cnn or "
                             "classical); set enabled false or add them")
        ins = auto.guidance.inspection
        if ins.leg_start_range_m == "from_beam":
            import math

            fls = enabled[name] if name is not None else next(c for c in enabled.values() if c.kind == "fls")
            vbw = resolve_geometry(fls).vertical_beamwidth_rad
            tilt = math.radians(fls.tilt_deg)
            if not (0.0 < tilt - 0.25 * vbw and tilt + 0.25 * vbw < 0.5 * math.pi):
                raise ValueError(f"autonomy.guidance.inspection.leg_start_range_m: from_beam needs a sonar looking down "
                                 f"at the seabed a quarter beam either side of its boresight (tilt {fls.tilt_deg} deg, "
                                 f"vertical beam {math.degrees(vbw):.1f} deg); give the leg ranges in m")
        if auto.tracking.enabled or auto.guidance.buddy.enabled:
            raise ValueError("autonomy.guidance.inspection.enabled: inspection cannot fly with autonomy.tracking or "
                             "buddy guidance (one guidance at a time); set one of them false")
        return self

    @model_validator(mode="after")
    def _mcm_needs_its_sonar(self) -> "Scenario":
        if self.mcm.mode == "full":
            cfg = self.sensors.enabled().get(self.mcm.sensor)
            if cfg is None or cfg.kind != "sss":
                raise ValueError(f"mcm.sensor: mode full needs an enabled side-scan (kind sss) sensor entry "
                                 f"named {self.mcm.sensor!r}")
        return self

    @model_validator(mode="after")
    def _link_has_its_surface_vehicle(self) -> "Scenario":
        comms = self.comms
        if comms.acoustic.enabled:
            name = comms.surface.vehicle
            if not self.vehicles:
                raise ValueError("comms.acoustic.enabled: the link needs a surface vehicle and vehicles has none "
                                 "(add vehicles.buoy with preset surface_buoy, as in cssn_sea_trial, or set "
                                 "comms.acoustic.enabled=false)")
            if name not in self.vehicles:
                raise ValueError(f"comms.surface.vehicle {name!r} is not a key of vehicles (allowed: "
                                 f"{', '.join(repr(k) for k in sorted(self.vehicles))})")
            if comms.surface.usbl_fixes and self.vehicles[name].usbl is None:
                raise ValueError(f"comms.surface.usbl_fixes needs vehicles.{name}.usbl (its USBL head)")
        return self
