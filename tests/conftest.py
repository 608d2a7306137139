"""Shared fixtures."""

from __future__ import annotations

import signal

import numpy as np
import pytest

from scenarios import load_scenario


def pytest_configure(config):
    """Ctrl-C tests need Python's own SIGINT handler. A shell without job control starts a
    background command (``pytest &``, ``nohup``) with SIGINT ignored, and Python then installs
    no handler, so those tests would fail for the way the suite was started, not for the code.
    Restore the default handler (children started by exec then get SIG_DFL, not SIG_IGN)."""
    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture(scope="session")
def cssn_scenario():
    return load_scenario("cssn_lawnmower")
