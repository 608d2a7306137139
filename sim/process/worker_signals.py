"""Ctrl-C and worker processes: the terminal sends SIGINT to the whole process group, so the
workers of ``auvsim dataset`` and of the pipelined ``auvsim run`` receive it too. They ignore
it (the parent, which handles it, stops them); a worker that raised ``KeyboardInterrupt``
would print a traceback. Between its start (fork, or spawn's fork and exec, both inherit the
signal mask) and the moment it ignores SIGINT, a worker holds it blocked because the parent
starts it under :func:`sigint_blocked`; :func:`ignore_sigint` then discards anything pending.
"""

from __future__ import annotations

import signal
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def sigint_blocked() -> Iterator[None]:
    """SIGINT blocked in the calling thread while the block runs (where POSIX signal masks
    exist; elsewhere nothing changes). Processes and threads started inside inherit the mask. A
    Ctrl-C that came meanwhile is raised, as ``KeyboardInterrupt``, when the block ends, or
    earlier where another thread of this process (one started before the block) took it."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def ignore_sigint() -> None:
    """In a worker process: ignore SIGINT, then unblock it (a Ctrl-C held back since the
    worker's start is discarded)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
