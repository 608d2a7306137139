"""Scenario files (YAML) and their typed, validated schema."""

from scenarios.load import ScenarioError, list_scenarios, load_scenario

__all__ = ["ScenarioError", "list_scenarios", "load_scenario"]
