"""The ``auvsim`` command line: one module per subcommand, argument checks in ``args``.

:func:`main` imports the command modules inside its own guard, so Ctrl-C while the
libraries load ends quietly with status 130.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status (see :mod:`sim.cli.app`)."""
    try:
        from sim.cli.app import main as run_main
    except KeyboardInterrupt:
        print("auvsim: interrupted", file=sys.stderr)
        return 130
    return run_main(argv)


__all__ = ["main"]
