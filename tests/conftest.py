"""Shared fixtures."""

from __future__ import annotations

import numpy as np
import pytest

from scenarios import load_scenario


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture(scope="session")
def cssn_scenario():
    return load_scenario("cssn_lawnmower")
