"""PMHA world model: anchors and the hypothesis tree (paper 000 V), built from estimation roles."""

import lazy_loader

# names resolved on first use, so importing one submodule (a config, say) loads no other
__getattr__, __dir__, __all__ = lazy_loader.attach(__name__, submod_attrs={
    "anchor": ["CLASS_NAMES", "Anchor"],
    "pmha": ["PMHA", "Hypothesis", "WorldObject"],
})
