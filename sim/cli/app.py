"""auvsim: closed-loop AUV mission simulator (MuJoCo, Fossen hydrodynamics, sonar, onboard autonomy).

Subcommands: ``scenarios``, ``validate``, ``run``, ``bench``, ``dataset``, ``sweep``, ``train-atr``,
``eval-atr``, ``realism``. Anything a user can get wrong (arguments, scenario files and keys, output
folders, model and dataset files) is reported as one line naming it, with exit status 2
and no traceback. An unexpected internal error prints a short traceback and exits 1;
``--debug`` (or ``AUVSIM_DEBUG=1``) prints the full one.

Exit status: 0 success, 1 internal error, 2 bad input, 3 mission aborted (outputs still
written), 130 interrupted (Ctrl-C), 143 terminated (SIGTERM).
"""

from __future__ import annotations

import argparse
import errno
import gc
import os
import signal
import threading
import sys
import traceback
from collections.abc import Callable, Sequence

from sim.cli import (bench_cmd, dataset_cmd, eval_atr_cmd, realism_cmd, run_cmd, scenario_cmds, sweep_cmd,
                     train_cmd)
from sim.cli.errors import (EXIT_INTERNAL_ERROR, EXIT_INTERRUPTED, EXIT_OK, EXIT_TERMINATED, EXIT_USAGE,
                            user_error_types)
from sim.process.gc_policy import set_loop_thresholds

DEBUG_ENV = "AUVSIM_DEBUG"


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (``auvsim run: error: ...``) and exit status 2."""

    def error(self, message: str):  # type: ignore[override]
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see {self.prog} --help)\n")

    def parse_args(self, args=None, namespace=None):  # type: ignore[override]
        # Unknown arguments are reported by the subcommand that received them.
        ns, extra = self.parse_known_args(args, namespace)
        if extra:
            prog = self.prog
            sub = getattr(ns, "command", None)
            if sub:
                prog = f"{self.prog} {sub}"
            self.exit(EXIT_USAGE, f"{prog}: error: unrecognized arguments: {' '.join(extra)} (see {prog} --help)\n")
        return ns


def package_version() -> str:
    """The installed ``auvsim`` distribution's version (``pyproject.toml``), or a note that
    it is not installed (the source tree run by path)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("auvsim")
    except PackageNotFoundError:
        return "unknown (not installed: pip install -e .)"


class _VersionAction(argparse.Action):
    """``--version``: print ``auvsim <version>`` and exit 0 (the version looked up only then)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):  # noqa: A002
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"auvsim {package_version()}")
        parser.exit(EXIT_OK)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="auvsim", description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--version", action=_VersionAction, help="print the version and exit")
    parser.add_argument("--debug", action="store_true",
                        help=f"print full tracebacks of internal errors (also {DEBUG_ENV}=1)")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for module in (scenario_cmds, run_cmd, bench_cmd, dataset_cmd, sweep_cmd, train_cmd, eval_atr_cmd, realism_cmd):
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


class Terminated(BaseException):
    """SIGTERM, raised in the main thread so outputs in progress are cleaned up."""


def _on_sigterm(signum: int, frame: object) -> None:
    raise Terminated()


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, or a usage error already printed as one line
        return int(exc.code or 0)
    func: Callable[[argparse.Namespace], int] = args.func
    debug = bool(args.debug or os.environ.get(DEBUG_ENV, "") not in ("", "0"))
    in_main_thread = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _on_sigterm) if in_main_thread else None
    gc_thresholds = set_loop_thresholds()
    try:
        return _dispatch(func, args, debug, f"auvsim {args.command}")
    finally:
        gc.set_threshold(*gc_thresholds)
        if in_main_thread:
            signal.signal(signal.SIGTERM, previous)


def _dispatch(func: Callable[[argparse.Namespace], int], args: argparse.Namespace, debug: bool, prog: str) -> int:
    """Run the subcommand; map what a user can cause to one line (``prog: error: ...``) and an
    exit status."""
    try:
        return int(func(args) or 0)
    except user_error_types() as exc:
        message = " ".join(str(exc).split("\n")[0].split()) if not isinstance(exc, _multi_line_types()) else str(exc)
        _say(f"{prog}: error: {message}")
        return EXIT_USAGE
    except BrokenPipeError:  # the reader went away (| head): stop quietly
        _silence_stdout()
        return EXIT_OK
    except OSError as exc:
        if exc.errno not in ENVIRONMENT_ERRNOS:
            _report_internal_error(exc, debug)
            return EXIT_INTERNAL_ERROR
        where = f"{exc.filename}: " if exc.filename else ""
        _say(f"{prog}: error: {where}{exc.strerror or exc} (nothing was kept from this run)")
        return EXIT_USAGE
    except KeyboardInterrupt:
        _say(f"{prog}: interrupted")
        return EXIT_INTERRUPTED
    except Terminated:
        _say(f"{prog}: terminated")
        return EXIT_TERMINATED
    except Exception as exc:  # noqa: BLE001 - the last resort that keeps bugs visible
        _report_internal_error(exc, debug)
        return EXIT_INTERNAL_ERROR


def script_parser(prog: str, description: str) -> argparse.ArgumentParser:
    """An argument parser for a study script under ``scripts/`` with the CLI's one-line usage
    errors (exit status 2)."""
    return _Parser(prog=prog, description=description)


def run_script(parser: argparse.ArgumentParser, func: Callable[[argparse.Namespace], int],
               argv: Sequence[str] | None = None) -> int:
    """Parse ``argv`` with ``parser`` (from :func:`script_parser`) and run ``func(args)`` as the
    CLI runs a subcommand: bad input (a scenario, a key, an output path: the CLI's user error
    types) is one line and exit status 2, Ctrl-C 130, a bug a short traceback and 1.

    Returns:
        the exit status.
    """
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    return _dispatch(func, args, os.environ.get(DEBUG_ENV, "") not in ("", "0"), parser.prog)


# Failures of the machine, not of auvsim: a full disk, a read-only or vanished folder.
ENVIRONMENT_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EACCES, errno.EPERM})


def _say(line: str) -> None:
    """Print one line to stderr; a closed stderr (| head) is not an error."""
    try:
        print(line, file=sys.stderr)
    except BrokenPipeError:
        pass


def _silence_stdout() -> None:
    """After a broken pipe, point stdout at /dev/null so the interpreter's flush at exit is quiet."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except OSError:
        pass


def _multi_line_types() -> tuple[type[BaseException], ...]:
    """Errors whose message lists several problems, one per line (scenario validation)."""
    from scenarios.load import ScenarioError

    return (ScenarioError,)


if __name__ == "__main__":
    sys.exit(main())
