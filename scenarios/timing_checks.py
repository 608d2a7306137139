"""Load-time checks of rates the mission loop cannot honour (:mod:`sim.mission`).

Run at load (:func:`scenarios.load.check_scenario`), so that a rate the loop would silently
change is refused with one line naming the key. The AUV's own sensors may run at any rate
(each fires at its own time, between physics steps too); the autonomy ticks every whole
number of physics steps, and an extra vehicle's sensors and autonomy are polled once per
autonomy tick.
"""

from __future__ import annotations

from scenarios.schema import Scenario


def timing_problems(scenario: Scenario) -> list[str]:
    """One line per rate of ``scenario`` the loop cannot honour, naming its key: an
    ``autonomy.rate_hz`` that does not divide ``physics.rate_hz``, and a
    ``vehicles.<name>.{gnss,compass,usbl,autonomy}.rate_hz`` above ``autonomy.rate_hz``."""
    problems = []
    physics_hz, auto_hz = scenario.physics.rate_hz, scenario.autonomy.rate_hz
    ratio = physics_hz / auto_hz
    if round(ratio) < 1 or abs(ratio - round(ratio)) > 1e-9 * ratio:
        steps = max(round(ratio), 1)
        problems.append(f"autonomy.rate_hz: {auto_hz:g} Hz must divide physics.rate_hz = {physics_hz:g} Hz (the "
                        f"autonomy ticks every whole number of physics steps; {physics_hz / steps:g} Hz would run); "
                        f"allowed: {physics_hz:g} / n for n = 1, 2, ...")
    for name, vcfg in scenario.vehicles.items():
        for key in ("gnss", "compass", "usbl", "autonomy"):
            cfg = getattr(vcfg, key, None)
            if cfg is None or not getattr(cfg, "enabled", True):
                continue
            if cfg.rate_hz > auto_hz * (1.0 + 1e-9):
                problems.append(f"vehicles.{name}.{key}.rate_hz: {cfg.rate_hz:g} Hz exceeds autonomy.rate_hz = "
                                f"{auto_hz:g} Hz (an extra vehicle is ticked once per autonomy period); allowed: "
                                f"at most {auto_hz:g}")
    return problems
