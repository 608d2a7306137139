"""The error raised for an ATR model file that is missing or unusable."""

from __future__ import annotations


class ModelFileError(ValueError):
    """An ATR model file is missing, unreadable, not ONNX, or breaks the model contract.

    The message names the file and what is wrong with it.
    """
