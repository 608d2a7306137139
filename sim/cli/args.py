"""Argument types that reject bad values where they enter, with the allowed range."""

from __future__ import annotations

import argparse
import math


def _checked(convert, ok, allowed: str):
    """An argparse type: ``convert`` the text, then require ``ok(value)``; errors say ``allowed``."""

    def parse(text: str):
        try:
            value = convert(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {allowed}, got {text!r}") from None
        if not ok(value):
            raise argparse.ArgumentTypeError(f"must be {allowed}, got {text}")
        return value

    return parse


def int_between(lo: int, hi: int):
    """An argparse type: a whole number from ``lo`` to ``hi``."""
    return _checked(int, lambda v: lo <= v <= hi, f"a whole number from {lo} to {hi}")


positive_int = _checked(int, lambda v: v >= 1, "a whole number >= 1")
MAX_DATASET_FRAMES = 1_000_000
frame_count = _checked(int, lambda v: 1 <= v <= MAX_DATASET_FRAMES, f"a whole number from 1 to {MAX_DATASET_FRAMES}")
non_negative_int = _checked(int, lambda v: 0 <= v <= 2**63 - 1, "a whole number from 0 to 2**63-1")
probability = _checked(float, lambda v: math.isfinite(v) and 0.0 <= v <= 1.0, "a number from 0 to 1")
positive_float = _checked(float, lambda v: math.isfinite(v) and v > 0.0, "a finite number > 0")
non_negative_float = _checked(float, lambda v: math.isfinite(v) and v >= 0.0, "a finite number >= 0")


def size_hw(text: str) -> tuple[int, int]:
    """``HxW`` in pixels, both multiples of 16 (network input and crop sizes)."""
    parts = str(text).lower().split("x")
    try:
        h, w = (int(v) for v in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must look like 240x448 (height x width, px), got {text!r}") from None
    if h < 16 or w < 16 or h % 16 or w % 16:
        raise argparse.ArgumentTypeError(f"height and width must be multiples of 16 and >= 16, got {text!r}")
    return h, w


def size_hw_or_none(text: str) -> tuple[int, int] | None:
    """``HxW`` (see :func:`size_hw`) or ``none``."""
    return None if str(text).lower() == "none" else size_hw(text)
