"""PMHA world model: anchors and the hypothesis tree (paper 000 V), built from estimation roles."""

from autonomy.world_model.anchor import CLASS_NAMES, Anchor
from autonomy.world_model.pmha import PMHA, Hypothesis, WorldObject

__all__ = ["CLASS_NAMES", "PMHA", "Anchor", "Hypothesis", "WorldObject"]
