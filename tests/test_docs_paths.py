"""Repository paths named in the docs and in docstrings / comments exist.

Scanned: README.md and every Markdown file under docs/, scripts/, sim/, autonomy/, scenarios/
and tests/ (all their text), and the docstrings and comments of the Python files under sim/,
autonomy/, scenarios/, scripts/ and tests/. A token that starts with one of the top-level
folders below and ends in a file extension, or ends with ``/`` (a folder), must exist
relative to the repository root; a relative Markdown link ``[text](target)`` must resolve
relative to its file, and its ``#anchor``, if any, must be a heading of the file it names.

Sources are cited by their key in ``docs/references.md``; the private notes file outside the
repository must not be named anywhere in the code or the docs. Nor may private issue numbers
(the word issue followed by a number, or a number after a hash sign): describe the fault instead.
"""

from __future__ import annotations

import ast
import io
import re
import tokenize
from functools import cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TOP = ("sim", "autonomy", "scenarios", "tests", "scripts", "docs")
PY_DIRS = ("sim", "autonomy", "scenarios", "scripts", "tests")
SKIP_DIRS = {"__pycache__", ".venv", ".ci-venv", "runs", "build", "dist", ".pytest_cache", ".git"}
EXTENSIONS = ("py", "md", "yaml", "yml", "png", "json", "jsonl", "onnx", "csv", "npz", "npy", "tif", "tiff",
              "stl", "xml", "toml", "txt", "ckpt", "msg")

# A path token: a top-level folder, then path characters; not preceded by a path character, so
# ``../docs/x.png`` (a relative link, checked as a link) and ``/tmp/sim/x.py`` are not tokens.
_PATH = re.compile(r"(?<![\w./\-])((?:" + "|".join(TOP) + r")/[\w./\-]*)")
_FILE_END = re.compile(r"\.(?:" + "|".join(EXTENSIONS) + r")$")
# [text](target) and ![alt](target); the target ends at whitespace or the closing bracket
_MD_LINK = re.compile(r"!?\[[^\]\n]*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
_PRIVATE_NOTES = re.compile(r"\b" + "REFERENCE" + r"\.md\b")
_ISSUE_NUMBER = re.compile(r"\b[Ii]ssue ?#?\d+|\(#\d+\)|(?<![\w&/#])#\d{2,}\b")


def _walk(folder: Path, suffix: str) -> list[Path]:
    return sorted(p for p in folder.rglob(f"*{suffix}")
                  if not SKIP_DIRS.intersection(p.relative_to(ROOT).parts) and p.is_file())


@cache
def markdown_files() -> tuple[Path, ...]:
    files = [ROOT / "README.md"]
    for top in TOP:
        files += _walk(ROOT / top, ".md")
    return tuple(files)


@cache
def python_files() -> tuple[Path, ...]:
    return tuple(p for top in PY_DIRS for p in _walk(ROOT / top, ".py"))


def path_tokens(text: str) -> list[str]:
    """Tokens of ``text`` that look like repository paths (a file with an extension, or a
    folder ending with ``/``); templates (``<key>``, ``{a,b}``, ``*``) end the token before them."""
    out = []
    for m in _PATH.finditer(text):
        tok = m.group(1).rstrip(".,;:")
        if _FILE_END.search(tok) or (tok.endswith("/") and "//" not in tok):
            out.append(tok)
    return out


def missing_paths(text: str) -> list[str]:
    return [t for t in path_tokens(text) if not (ROOT / t).exists()]


def python_prose(source: str) -> str:
    """The docstrings (every bare string statement) and the comments of a Python source."""
    parts = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str):
            parts.append(node.value.value)
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type == tokenize.COMMENT:
            parts.append(tok.string)
    return "\n".join(parts)


def github_anchor(heading: str) -> str:
    """The anchor GitHub gives a Markdown heading."""
    text = re.sub(r"[`*_]|\[([^\]]*)\]\([^)]*\)", lambda m: m.group(1) or "", heading.strip().lower())
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


@cache
def anchors(md: Path) -> frozenset[str]:
    text = re.sub(r"^```.*?^```", "", md.read_text(), flags=re.S | re.M)  # no headings in code blocks
    return frozenset(github_anchor(m.group(1)) for m in re.finditer(r"^#{1,6}\s+(.+?)\s*#*$", text, re.M))


def broken_links(md: Path, text: str) -> list[str]:
    """Relative links of ``text`` (the contents of ``md``) whose target or anchor is missing."""
    out = []
    for m in _MD_LINK.finditer(text):
        target = m.group(1)
        if re.match(r"^[a-z][a-z0-9+.\-]*:", target, re.I):  # http:, https:, mailto:
            continue
        path, _, frag = target.partition("#")
        dest = (md.parent / path).resolve() if path else md
        if not dest.exists():
            out.append(target)
        elif frag and dest.suffix == ".md" and frag not in anchors(dest):
            out.append(target)
    return out


def _rel(p: Path) -> str:
    return p.relative_to(ROOT).as_posix()


@cache
def prose() -> tuple[tuple[Path, str], ...]:
    """(file, text to scan for paths) of every scanned file. A Python file is parsed for its
    docstrings and comments only when its whole source names a missing path (a docstring or a
    comment is source text, so a clean source has clean prose): parsing all of them is slow."""
    out = [(md, md.read_text()) for md in markdown_files()]
    for py in python_files():
        source = py.read_text()
        if missing_paths(source):
            out.append((py, python_prose(source)))
    return tuple(out)


# --------------------------------------------------------------------------- the checker can fail

def test_checker_reports_a_made_up_path_and_a_broken_link(tmp_path):
    made_up = "sim/" + "no_such_module_xyz.py"
    text = f"See `{made_up}`, `docs/` and (`tests/sim/dynamics/test_vehicle.py`, docs/speed/<key>.json)."
    assert path_tokens(text) == [made_up, "docs/", "tests/sim/dynamics/test_vehicle.py", "docs/speed/"]
    assert missing_paths(text) == [made_up]
    assert missing_paths("scripts/" + "no_such_folder/") == ["scripts/no_such_folder/"]
    assert missing_paths("not a path: runs/cssn/metrics.json, /tmp/sim/x.py, ../docs/x.png") == []
    src = f'"""Module docs: {made_up}."""\nx = "{made_up}"  # and tests/{"nope"}.py\n'
    assert missing_paths(python_prose(src)) == [made_up, "tests/nope.py"]  # the code string is not prose

    md = tmp_path / "page.md"
    md.write_text("# A page\n\n## Section two (`x`)\n")
    (tmp_path / "other.md").write_text("# Other\n")
    body = ("[ok](other.md) [anchor](#section-two-x) [bad](missing.md) [bad anchor](other.md#nope) "
            "[web](https://example.com/x.md) ![img](gone.png)")
    assert broken_links(md, body) == ["missing.md", "other.md#nope", "gone.png"]

    assert _PRIVATE_NOTES.search("see " + "REFERENCE" + ".md section 7")
    assert not _PRIVATE_NOTES.search("docs/references.md")
    for bad in ("issue " + "26", "Issue #" + "12", "fixed (#" + "33)", "see #" + "45"):
        assert _ISSUE_NUMBER.search(bad), bad
    for fine in ("rerun-io/rerun/issues/12623", "colour #1f77b4", "10 issues", "&#39;"):
        assert not _ISSUE_NUMBER.search(fine), fine


# --------------------------------------------------------------------------- the repository

def test_every_scanned_file_set_is_found():
    names = {_rel(p) for p in markdown_files()}
    assert {"README.md", "docs/references.md", "scripts/README.md"} <= names
    assert any(n.startswith("docs/studies/") for n in names)
    assert len(python_files()) > 100


def test_paths_named_in_docs_and_docstrings_exist():
    bad = [f"{_rel(f)}: {tok}" for f, text in prose() for tok in missing_paths(text)]
    assert not bad, "paths that do not exist:\n" + "\n".join(bad)


def test_relative_markdown_links_resolve():
    bad = [f"{_rel(md)}: {t}" for md in markdown_files() for t in broken_links(md, md.read_text())]
    assert not bad, "broken links:\n" + "\n".join(bad)


@pytest.mark.parametrize("check", ["private_notes", "issue_numbers"])
def test_no_private_notes_file_or_issue_numbers(check):
    pattern = _PRIVATE_NOTES if check == "private_notes" else _ISSUE_NUMBER
    files = [ROOT / "README.md", ROOT / "pyproject.toml", *markdown_files(), *python_files()]
    for top in ("sim", "autonomy", "scenarios", "scripts", "docs"):
        files += _walk(ROOT / top, ".yaml")
    me = Path(__file__).resolve()
    bad = [f"{_rel(f)}:{i}: {line.strip()}" for f in dict.fromkeys(files) if f.resolve() != me
           for i, line in enumerate(f.read_text().splitlines(), 1) if pattern.search(line)]
    what = ("cite sources by their docs/references.md key" if check == "private_notes"
            else "describe the fault, not a private issue number")
    assert not bad, f"{what}:\n" + "\n".join(bad)
