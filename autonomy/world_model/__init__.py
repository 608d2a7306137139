"""PMHA world model: anchors, hypothesis tree and ranked assignments (paper 000 V)."""

from autonomy.world_model.anchor import CLASS_NAMES, Anchor
from autonomy.world_model.murty import murty_k_best
from autonomy.world_model.pmha import PMHA, Hypothesis, WorldObject

__all__ = ["CLASS_NAMES", "PMHA", "Anchor", "Hypothesis", "WorldObject", "murty_k_best"]
