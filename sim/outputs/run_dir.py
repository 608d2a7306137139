"""Output folders that never lose what is already on disk.

A command that writes results (``auvsim run``, ``auvsim dataset``) names an output folder.
:func:`check_output_dir` refuses, before anything is written, every folder whose loss or
mixing would hurt: the current directory or any folder that contains it, the home
directory or a folder containing it, the filesystem root, a path that is a file, and a
non-empty folder that is not the command's own earlier output. The command's own outputs
carry a marker file (:data:`MARKER_FILE`) naming their kind.

:class:`StagedOutput` writes a run into a hidden ``.<name>.partial`` sibling and moves it
into place only when complete; an old run folder being replaced is removed only after the
new one is in place. An interrupted or failed run removes its partial folder.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path

MARKER_FILE = ".auvsim-output"
INCOMPLETE_FILE = "INCOMPLETE"


class OutputDirError(ValueError):
    """An output folder that cannot or must not be written; the message names it and why."""


def _resolved(path: str | os.PathLike[str], arg: str) -> Path:
    text = os.fspath(path)
    if not text.strip():
        raise OutputDirError(f"{arg}: must name a folder, got an empty string")
    if "\0" in text:
        raise OutputDirError(f"{arg} {text!r}: a path cannot contain a NUL character")
    return Path(text).expanduser().resolve()


def read_marker(folder: Path) -> dict | None:
    """The marker of an auvsim output folder (``{"kind": ...}``), or None if it has none."""
    try:
        data = json.loads((folder / MARKER_FILE).read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


RUN_FILES = frozenset({"metrics.json", "scenario.yaml", "trajectory.csv", "world_model.json",
                       "surface_world_model.json", "map.png", "recording.rrd", "rosbag", "xtf", "ping360",
                       "tracking_error.png", "tracking_boxplot.png"})


def is_output_of(folder: Path, kind: str) -> bool:
    """Whether ``folder`` holds an earlier auvsim output of ``kind``.

    Recognised by the marker, or for folders written before markers existed: a run folder
    holding ``metrics.json`` and only run files; a dataset folder holding ``manifest.json``
    with a ``generator_version``.
    """
    marker = read_marker(folder)
    if marker is not None:
        return marker.get("kind") == kind
    names = {p.name for p in folder.iterdir()}
    if kind == "run":
        return "metrics.json" in names and names <= RUN_FILES
    if kind == "dataset":
        try:
            manifest = json.loads((folder / "manifest.json").read_text())
        except (OSError, ValueError):
            return False
        return isinstance(manifest, dict) and "generator_version" in manifest
    return False


def write_marker(folder: Path, kind: str) -> None:
    """Mark ``folder`` as an auvsim output of ``kind`` (``run``, ``dataset``), listing the
    entries it holds (an ``--overwrite`` may delete those and no others)."""
    files = sorted(p.name for p in folder.iterdir() if p.name not in (MARKER_FILE, INCOMPLETE_FILE))
    (folder / MARKER_FILE).write_text(json.dumps({"kind": kind, "tool": "auvsim", "files": files}) + "\n")


def _protected(out: Path) -> str | None:
    """Why ``out`` must never be an output folder, or None."""
    cwd = Path.cwd().resolve()
    home = Path.home().resolve()
    if out == Path(out.anchor):
        return "is the filesystem root"
    if out == cwd:
        return "is the current directory"
    if cwd.is_relative_to(out):
        return "contains the current directory"
    if out == home:
        return "is the home directory"
    if home.is_relative_to(out):
        return "contains the home directory"
    return None


def _check_parent_writable(out: Path, arg: str) -> None:
    parent = out.parent
    probe = parent
    while not probe.exists():
        probe = probe.parent
    if not probe.is_dir():
        raise OutputDirError(f"{arg} {out}: {probe} is a file, not a folder")
    if not os.access(probe, os.W_OK | os.X_OK):
        raise OutputDirError(f"{arg} {out}: cannot create it here ({probe} is not writable)")
    try:
        parent.mkdir(parents=True, exist_ok=True)
        # A real probe: permissions alone do not tell (root on /proc, read-only mounts).
        os.rmdir(tempfile.mkdtemp(prefix=".auvsim-probe-", dir=parent))
    except OSError as exc:
        raise OutputDirError(f"{arg} {out}: cannot create a folder in {parent}: {exc.strerror or exc}") from None


def check_output_dir(path: str | os.PathLike[str], *, kind: str, overwrite: bool = False,
                     resume: bool = False, arg: str = "--out") -> Path:
    """Validate an output folder before anything is written; returns its resolved path.

    Args:
        path: the folder the user named.
        kind: what the command writes (``run``, ``dataset``); an existing non-empty folder
            is accepted only if its marker has this kind.
        overwrite: an earlier output of ``kind`` may be replaced (``run --overwrite``).
        resume: an earlier output of ``kind`` may be continued in place (``dataset``).
        arg: the argument name used in messages.

    Raises:
        OutputDirError: the folder is protected (root, home, the current directory or a
            folder containing either), is a file, cannot be created, or holds files that
            are not an earlier output of ``kind`` (or ``overwrite``/``resume`` is not set).
    """
    out = _resolved(path, arg)
    why = _protected(out)
    if why:
        raise OutputDirError(f"{arg} {path}: refusing to write there: it {why} ({out}); name a new folder")
    if out.exists() and not out.is_dir():
        raise OutputDirError(f"{arg} {out}: is a file, not a folder")
    if out.is_dir():
        try:
            entries = [p.name for p in out.iterdir()]
        except OSError as exc:
            raise OutputDirError(f"{arg} {out}: cannot read it: {exc.strerror or exc}") from None
        if entries:
            if not is_output_of(out, kind):
                other = (read_marker(out) or {}).get("kind")
                what = f"an auvsim {other} output, not a {kind}" if isinstance(other, str) else (
                    f"files that are not an auvsim {kind} output")
                raise OutputDirError(f"{arg} {out}: folder exists and holds {what}; refusing to touch it "
                                     "(name a new folder)")
            if not (overwrite or resume):
                raise OutputDirError(f"{arg} {out}: holds an earlier {kind}; pass --overwrite to replace it, "
                                     "or name a new folder")
            if overwrite and kind == "run":
                written = (read_marker(out) or {}).get("files", [])
                extra = sorted(set(entries) - RUN_FILES - set(written if isinstance(written, list) else [])
                               - {MARKER_FILE})
                if extra:
                    shown = ", ".join(extra[:5]) + (f" and {len(extra) - 5} more" if len(extra) > 5 else "")
                    raise OutputDirError(f"{arg} {out}: holds files an auvsim run did not write ({shown}); "
                                         "--overwrite would delete them: move them out first, or name a new folder")
        if not os.access(out, os.W_OK | os.X_OK):
            raise OutputDirError(f"{arg} {out}: folder is not writable")
    _check_parent_writable(out, arg)
    return out


class StagedOutput:
    """Write into ``.<name>.partial`` next to ``out``; :meth:`commit` moves it into place.

    Use as a context manager: leaving the block with an exception (including Ctrl-C)
    removes the partial folder; the existing ``out`` is untouched until commit.

    Args:
        out: a folder already accepted by :func:`check_output_dir`.
        kind: marker kind written into the committed folder.

    Raises:
        OutputDirError: a foreign folder already sits where the partial folder goes.
    """

    def __init__(self, out: Path, kind: str) -> None:
        self.out = Path(out)
        self.kind = kind
        self.partial = self.out.parent / f".{self.out.name}.partial"
        if self.partial.is_relative_to(self.out):
            raise OutputDirError(f"{self.out}: the output folder would contain its own partial folder")

    def __enter__(self) -> Path:
        if self.partial.exists():
            if not (self.partial / INCOMPLETE_FILE).is_file():
                raise OutputDirError(f"{self.partial}: exists and is not an unfinished auvsim output; "
                                     "move it away first")
            shutil.rmtree(self.partial)
        self.partial.mkdir(parents=True)
        (self.partial / INCOMPLETE_FILE).write_text("this run did not finish; results here are not valid\n")
        return self.partial

    def commit(self) -> Path:
        """Move the finished partial folder to ``out``; an earlier output there goes last."""
        write_marker(self.partial, self.kind)
        (self.partial / INCOMPLETE_FILE).unlink()
        old = None
        if self.out.exists():
            old = self.out.parent / f".{self.out.name}.old-{os.getpid()}"
            os.replace(self.out, old)
        os.replace(self.partial, self.out)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return self.out

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is not None and self.partial.exists():
            shutil.rmtree(self.partial, ignore_errors=True)
