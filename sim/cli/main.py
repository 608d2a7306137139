"""The ``auvsim`` command line.

Subcommands: ``scenarios``, ``validate``, ``run``, ``bench``, ``dataset``, ``sweep``, ``train-atr``,
``eval-atr``. Anything a user can get wrong (arguments, scenario files and keys, output
folders, model and dataset files) is reported as one line naming it, with exit status 2
and no traceback. An unexpected internal error prints a short traceback and exits 1;
``--debug`` (or ``AUVSIM_DEBUG=1``) prints the full one.

Exit status: 0 success, 1 internal error, 2 bad input, 3 mission aborted (outputs still
written), 130 interrupted.
"""

from __future__ import annotations

import argparse
import os
import sys
import traceback
from collections.abc import Callable, Sequence

from sim.cli import bench_cmd, dataset_cmd, eval_atr_cmd, run_cmd, scenario_cmds, sweep_cmd, train_cmd
from sim.cli.errors import EXIT_INTERNAL_ERROR, EXIT_INTERRUPTED, EXIT_USAGE, user_error_types

DEBUG_ENV = "AUVSIM_DEBUG"


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (``auvsim run: error: ...``) and exit status 2."""

    def error(self, message: str):  # type: ignore[override]
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="auvsim", description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--debug", action="store_true",
                        help=f"print full tracebacks of internal errors (also {DEBUG_ENV}=1)")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for module in (scenario_cmds, run_cmd, bench_cmd, dataset_cmd, sweep_cmd, train_cmd, eval_atr_cmd):
        module.add_parser(sub)
    return parser


def _report_internal_error(exc: BaseException, full: bool) -> None:
    if full:
        traceback.print_exception(exc)
    else:
        frames = traceback.extract_tb(exc.__traceback__)[-3:]
        print("Traceback (last frames; rerun with --debug for the full one):", file=sys.stderr)
        print("".join(traceback.format_list(frames)), end="", file=sys.stderr)
        print("".join(traceback.format_exception_only(exc)), end="", file=sys.stderr)
    print("auvsim: internal error (a bug, not your input): please report it with the lines above",
          file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, or a usage error already printed as one line
        return int(exc.code or 0)
    func: Callable[[argparse.Namespace], int] = args.func
    debug = bool(args.debug or os.environ.get(DEBUG_ENV, "") not in ("", "0"))
    try:
        return int(func(args) or 0)
    except user_error_types() as exc:
        message = " ".join(str(exc).split("\n")[0].split()) if not isinstance(exc, _multi_line_types()) else str(exc)
        print(f"auvsim {args.command}: error: {message}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print(f"auvsim {args.command}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:  # noqa: BLE001 - the last resort that keeps bugs visible
        _report_internal_error(exc, debug)
        return EXIT_INTERNAL_ERROR


def _multi_line_types() -> tuple[type[BaseException], ...]:
    """Errors whose message lists several problems, one per line (scenario validation)."""
    from scenarios.load import ScenarioError

    return (ScenarioError,)


if __name__ == "__main__":
    sys.exit(main())
