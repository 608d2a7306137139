"""The error a full-mode MCM run raises for input a user got wrong."""

from __future__ import annotations


class NoTileError(ValueError):
    """A full-mode run too short (or without a pinging side-scan) to form one tile: bad input;
    the message names ``duration_s`` and ``mcm.tile.tile_period_s``."""
