"""Errors a user can cause, reported by the CLI as one line with exit status 2."""

from __future__ import annotations

from autonomy.atr.model_file import ModelFileError
from sim.dataset.errors import DatasetError
from sim.mcm.errors import NoTileError
from sim.outputs.run_dir import OutputDirError


class CliError(Exception):
    """A user error: the message names the argument, key or file and what is allowed."""


EXIT_OK = 0
EXIT_INTERNAL_ERROR = 1
EXIT_USAGE = 2
EXIT_MISSION_ABORTED = 3
EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 143


def user_error_types() -> tuple[type[BaseException], ...]:
    """Exception types that mean bad input (one line, exit 2), not a bug."""
    from scenarios.load import ScenarioError
    from sim.sweep.runner import SweepError

    return (CliError, ScenarioError, OutputDirError, DatasetError, ModelFileError, SweepError, NoTileError)
