"""Scenario files (YAML) and their typed, validated schema."""

import lazy_loader

# names resolved on first use, so importing one submodule (a config, say) loads no other
__getattr__, __dir__, __all__ = lazy_loader.attach(__name__, submod_attrs={
    "load": ["ScenarioError", "list_scenarios", "load_scenario"],
})
