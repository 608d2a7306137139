"""Checks that the names a scenario's sensors and trackers refer to resolve: hull sites of
sensor mounts, the USBL's transponder, the sensors and mover the target tracker uses, the sonar
the survey's ATR reads, and the scanning sonar and basin the pool / tank localisation needs.

Run at load (:func:`scenarios.load.check_scenario`), so ``auvsim validate`` and ``auvsim run``
report a dangling name as one line naming the key and what is allowed, instead of failing
when the mission is built.
"""

from __future__ import annotations

from scenarios.schema import Scenario

#: The kinds the target tracker reads (paper 004): a forward-looking sonar and a USBL.
TRACKING_SONAR_KIND = "fls"
TRACKING_USBL_KIND = "usbl"


def _hull_sites(scenario: Scenario) -> set[str] | None:
    """Names of the AUV hull's sites (sensor mounts and ``thruster_<name>``); None when the
    preset cannot be read (its own check reports that)."""
    from scenarios.vehicle_params import SENSOR_NAMES, load_vehicle_params

    try:
        params = load_vehicle_params(scenario.vehicle)
    except (OSError, ValueError):
        return None
    return {n for n in SENSOR_NAMES if n in params.sensors} | {f"thruster_{n}" for n in params.layout.names}


def mount_problems(scenario: Scenario) -> list[str]:
    """An enabled sensor without ``mount_pos_body_m`` must sit at a hull site of the vehicle
    (``mount_site``, default the entry's name)."""
    sites = _hull_sites(scenario)
    if sites is None:
        return []
    problems = []
    for name, cfg in scenario.sensors.enabled().items():
        if cfg.mount_pos_body_m is not None:
            continue
        site = cfg.mount_site or name
        if site not in sites:
            key = "mount_site" if cfg.mount_site else "mount_pos_body_m"
            problems.append(f"sensors.{name}.{key}: the {scenario.vehicle.model} hull has no site {site!r}; set "
                            f"mount_pos_body_m: [x, y, z] (FRD, m) or mount_site to one of "
                            f"{', '.join(sorted(s for s in sites if not s.startswith('thruster_')))}")
    return problems


def transponder_problems(scenario: Scenario) -> list[str]:
    """A USBL's ``transponder`` is ``beacon`` or names a mover or target of ``world``."""
    movers = [m.name for m in scenario.world.movers]
    objects = movers + [t.name for t in scenario.world.targets]
    problems = []
    for name, cfg in scenario.sensors.enabled().items():
        if cfg.kind != TRACKING_USBL_KIND or cfg.transponder == "beacon" or cfg.transponder in objects:
            continue
        allowed = "'beacon' or a world.movers / world.targets name" + (f" ({', '.join(objects)})" if objects
                                                                         else " (the scenario has none)")
        problems.append(f"sensors.{name}.transponder: {cfg.transponder!r} is not in the scene; allowed: {allowed}")
    return problems


def tracking_problems(scenario: Scenario) -> list[str]:
    """With ``autonomy.tracking.enabled``: its ``transponder`` names a mover, its
    ``sonar_sensor`` and ``usbl_sensor`` name enabled sensors of kind fls and usbl, and that
    USBL interrogates the same transponder; ``autonomy.guidance.buddy`` needs the tracker."""
    tr = scenario.autonomy.tracking
    problems = []
    if scenario.autonomy.guidance.buddy.enabled and not tr.enabled:
        problems.append("autonomy.guidance.buddy.enabled: the buddy observer follows the tracker's estimate; "
                        "set autonomy.tracking.enabled: true (or buddy.enabled: false)")
    if not tr.enabled:
        return problems
    movers = [m.name for m in scenario.world.movers]
    objects = movers + [t.name for t in scenario.world.targets]
    if tr.transponder not in movers:
        problems.append(f"autonomy.tracking.transponder: {tr.transponder!r} is not a mover; allowed: a world.movers "
                        f"name ({', '.join(movers) if movers else 'the scenario has none: add one under world.movers'})")
    enabled = scenario.sensors.enabled()
    for key, sensor, kind in (("sonar_sensor", tr.sonar_sensor, TRACKING_SONAR_KIND),
                              ("usbl_sensor", tr.usbl_sensor, TRACKING_USBL_KIND)):
        cfg = enabled.get(sensor)
        if cfg is None or cfg.kind != kind:
            names = [n for n, c in enabled.items() if c.kind == kind]
            what = "is not an enabled sensor" if cfg is None else f"is a {cfg.kind} sensor"
            problems.append(f"autonomy.tracking.{key}: {sensor!r} {what}; the tracker needs a {kind} sensor"
                            f" ({'enabled: ' + ', '.join(names) if names else f'add one under sensors.{sensor}'})")
        elif (kind == TRACKING_USBL_KIND and cfg.transponder != tr.transponder and tr.transponder in movers
              and (cfg.transponder == "beacon" or cfg.transponder in objects)):  # else reported above
            problems.append(f"sensors.{sensor}.transponder: {cfg.transponder!r} differs from "
                            f"autonomy.tracking.transponder {tr.transponder!r}; the tracker would get no USBL fix")
    return problems


#: The kind of sonar the survey's ATR reads.
ATR_SONAR_KIND = "fls"


def atr_sonar_name(scenario: Scenario) -> str | None:
    """The sensor entry whose frames the survey's perception (ATR -> geolocalisation -> world
    model) processes: ``autonomy.atr.sonar_sensor``, or by default the first enabled entry of
    kind fls; None when there is none (or the named one is not an enabled fls entry, which
    :func:`atr_sonar_problems` reports)."""
    enabled = scenario.sensors.enabled()
    name = scenario.autonomy.atr.sonar_sensor
    if name is not None:
        cfg = enabled.get(name)
        return name if cfg is not None and cfg.kind == ATR_SONAR_KIND else None
    return next((n for n, c in enabled.items() if c.kind == ATR_SONAR_KIND), None)


def atr_sonar_problems(scenario: Scenario) -> list[str]:
    """``autonomy.atr.sonar_sensor``, when set, names an enabled sensor of kind fls."""
    name = scenario.autonomy.atr.sonar_sensor
    if name is None:
        return []
    enabled = scenario.sensors.enabled()
    cfg = enabled.get(name)
    if cfg is not None and cfg.kind == ATR_SONAR_KIND:
        return []
    names = [n for n, c in enabled.items() if c.kind == ATR_SONAR_KIND]
    what = "is not an enabled sensor" if cfg is None else f"is a {cfg.kind} sensor"
    return [f"autonomy.atr.sonar_sensor: {name!r} {what}; the ATR reads an {ATR_SONAR_KIND} sensor (allowed: "
            + (", ".join(names) + ", or null for the first" if names else "none enabled: add one under sensors")
            + ")"]


#: The basin wall shape each scanning-sonar localisation method fits (paper 002).
MSIS_METHOD_BASIN = {"circle": "circular", "walls": "rectangular"}


def msis_localization_problems(scenario: Scenario) -> list[str]:
    """``autonomy.msis_localization.method`` other than ``none`` needs an enabled msis sensor
    and walls of the shape it fits (``circle``: a circular basin, ``walls``: a rectangular one)."""
    method = scenario.autonomy.msis_localization.method
    if method == "none":
        return []
    problems = []
    if not any(c.kind == "msis" for c in scenario.sensors.enabled().values()):
        problems.append(f"autonomy.msis_localization.method: {method!r} needs an enabled msis sensor "
                        "(sensors: {msis: {...}}), or method: none")
    shape = scenario.world.basin.shape
    if shape != MSIS_METHOD_BASIN[method]:
        fits = next(m for m, b in MSIS_METHOD_BASIN.items() if b == shape) if shape in MSIS_METHOD_BASIN.values() else None
        problems.append(f"autonomy.msis_localization.method: {method!r} fits a {MSIS_METHOD_BASIN[method]} basin but "
                        f"world.basin.shape is {shape!r}; allowed here: "
                        + (f"{fits!r} or 'none'" if fits else "'none'"))
    return problems


def sensor_link_problems(scenario: Scenario) -> list[str]:
    """Every problem of :func:`mount_problems`, :func:`transponder_problems`,
    :func:`tracking_problems`, :func:`atr_sonar_problems` and
    :func:`msis_localization_problems`, one line each."""
    return (mount_problems(scenario) + transponder_problems(scenario) + tracking_problems(scenario)
            + atr_sonar_problems(scenario) + msis_localization_problems(scenario))
