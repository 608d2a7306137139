"""Scripts that start ``spawn`` workers without the ``if __name__ == "__main__":`` guard.

``spawn`` runs the main script again in each new process; without the guard the script's
work (a mission with workers, a dataset) would start over there and start workers of its own.
Entry points call :func:`exit_if_spawn_reimport` first: in such a re-run they end the process
quietly with :data:`NO_MAIN_GUARD_EXIT`, which the parent recognises (:func:`main_guard_missing`)
and turns into one clear error.
"""

from __future__ import annotations

import multiprocessing as mp
from typing import Any

NO_MAIN_GUARD_EXIT = 86  # a worker's exit status when spawn found the script unguarded


def exit_if_spawn_reimport() -> None:
    """End this process with :data:`NO_MAIN_GUARD_EXIT` if it is a spawned worker still
    re-running the main script (the script lacks the ``__main__`` guard)."""
    if getattr(mp.current_process(), "_inheriting", False):
        raise SystemExit(NO_MAIN_GUARD_EXIT)


def _nothing() -> None:
    """A probe worker's whole task."""


def main_guard_missing(ctx: Any) -> bool:
    """Whether a process started with ``ctx`` (a ``spawn`` context) ends with
    :data:`NO_MAIN_GUARD_EXIT`: one short-lived probe process (about the time of the script's
    imports)."""
    probe = ctx.Process(target=_nothing, name="auvsim-spawn-probe")
    probe.start()
    probe.join()
    return probe.exitcode == NO_MAIN_GUARD_EXIT
