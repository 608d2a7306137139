"""Turn a gym constructor's ``scenario`` argument into a validated :class:`Scenario`."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from scenarios.load import apply_overrides, load_scenario, scenario_from_dict
from scenarios.schema import Scenario


def resolve_scenario(scenario: str | Path | Scenario, overrides: Sequence[str] = ()) -> Scenario:
    """A shipped scenario name, a YAML path or a :class:`Scenario`, with ``key.path=value``
    overrides applied (errors name the key and the allowed values)."""
    if isinstance(scenario, Scenario):
        if not overrides:
            return scenario
        data = apply_overrides(scenario.model_dump(mode="python"), list(overrides))
        return scenario_from_dict(data, f"<scenario {scenario.name}>")
    if isinstance(scenario, (str, Path)):
        return load_scenario(scenario, list(overrides))
    raise TypeError(f"scenario must be a scenario name, a YAML path or a Scenario, got {type(scenario).__name__}")
