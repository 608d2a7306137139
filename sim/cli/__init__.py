"""The ``auvsim`` command line: one module per subcommand, argument checks in ``args``."""

from sim.cli.main import main

__all__ = ["main"]
