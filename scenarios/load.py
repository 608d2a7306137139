"""Load, override and validate scenario files.

Errors name the file, the dotted key path and what is allowed, as a single
:class:`ScenarioError` the CLI prints without a traceback.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Any

import yaml
from pydantic import ValidationError

from scenarios.schema import Scenario


class ScenarioError(ValueError):
    """A scenario could not be loaded; the message says where and why."""


def scenarios_dir() -> Path:
    """Folder of the shipped scenario files."""
    return Path(str(resources.files("scenarios")))


def list_scenarios() -> dict[str, str]:
    """Shipped scenario names -> one-line description."""
    out: dict[str, str] = {}
    for path in sorted(scenarios_dir().glob("*.yaml")):
        try:
            data = yaml.safe_load(path.read_text()) or {}
            desc = str(data.get("description", "")).strip().splitlines()[0]
        except (yaml.YAMLError, IndexError, AttributeError):
            desc = ""
        out[path.stem] = desc
    return out


def resolve_path(name_or_path: str | Path) -> Path:
    """A shipped scenario name (``cssn_lawnmower``) or a path to a YAML file."""
    p = Path(name_or_path)
    if p.suffix in (".yaml", ".yml") or p.exists() or "/" in str(name_or_path):
        if not p.is_file():
            raise ScenarioError(f"{p}: scenario file not found")
        return p
    shipped = scenarios_dir() / f"{name_or_path}.yaml"
    if not shipped.is_file():
        names = ", ".join(list_scenarios()) or "none"
        raise ScenarioError(f"{name_or_path}: no such scenario file or shipped scenario (shipped: {names})")
    return shipped


def _parse_override(item: str, source: str) -> tuple[list[str], Any]:
    if "=" not in item:
        raise ScenarioError(f"{source}: override {item!r} must look like key.path=value")
    key, raw = item.split("=", 1)
    key = key.strip()
    if not key or any(not part for part in key.split(".")):
        raise ScenarioError(f"{source}: override {item!r} has an empty key")
    try:
        value = yaml.safe_load(raw) if raw.strip() else ""
    except yaml.YAMLError as exc:
        raise ScenarioError(f"{source}: override {key}: cannot parse value {raw!r}: {exc}") from None
    return key.split("."), value


def apply_overrides(data: dict[str, Any], overrides: list[str] | tuple[str, ...], source: str) -> dict[str, Any]:
    """Apply ``key.path=value`` overrides (values parsed as YAML) to a raw mapping."""
    for item in overrides:
        path, value = _parse_override(item, source)
        node: Any = data
        for i, part in enumerate(path[:-1]):
            if isinstance(node, list):
                if not part.isdigit() or int(part) >= len(node):
                    raise ScenarioError(f"{source}: override {'.'.join(path)}: {'.'.join(path[: i + 1])} is not a valid list index")
                node = node[int(part)]
                continue
            if not isinstance(node, dict):
                raise ScenarioError(f"{source}: override {'.'.join(path)}: {'.'.join(path[:i])} is not a mapping")
            node = node.setdefault(part, {})
        last = path[-1]
        if isinstance(node, list):
            if not last.isdigit() or int(last) >= len(node):
                raise ScenarioError(f"{source}: override {'.'.join(path)}: not a valid list index")
            node[int(last)] = value
        elif isinstance(node, dict):
            node[last] = value
        else:
            raise ScenarioError(f"{source}: override {'.'.join(path)}: parent is not a mapping")
    return data


def _format_validation_error(exc: ValidationError, source: str) -> str:
    lines = [f"{source}: invalid scenario ({exc.error_count()} error{'s' if exc.error_count() != 1 else ''})"]
    for err in exc.errors(include_url=False):
        loc = ".".join(str(p) for p in err["loc"]) or "(top level)"
        kind = err["type"]
        msg = err["msg"]
        if kind == "extra_forbidden":
            allowed = _allowed_keys(err["loc"][:-1])
            msg = f"unknown key; allowed keys here: {', '.join(allowed)}" if allowed else "unknown key"
        elif kind == "literal_error":
            msg = msg.replace("Input should be", "allowed values:")
        given = err.get("input")
        given_txt = "" if kind in ("extra_forbidden", "missing") or isinstance(given, dict) else f" (got {given!r})"
        lines.append(f"  {loc}: {msg}{given_txt}")
    return "\n".join(lines)


def _allowed_keys(loc: tuple[Any, ...]) -> list[str]:
    """Field names of the model at ``loc`` inside :class:`Scenario`."""
    import typing

    from pydantic import BaseModel

    model: Any = Scenario
    for part in loc:
        if isinstance(part, int):
            continue
        field = model.model_fields.get(part) if isinstance(model, type) and issubclass(model, BaseModel) else None
        if field is None:
            return []
        ann = field.annotation
        for _ in range(3):
            args = typing.get_args(ann)
            if isinstance(ann, type) and issubclass(ann, BaseModel):
                break
            cands = [a for a in args if isinstance(a, type) and issubclass(a, BaseModel)]
            if not cands:
                ann = None
                break
            ann = cands[0]
        if ann is None:
            return []
        model = ann
    return list(model.model_fields) if isinstance(model, type) and issubclass(model, BaseModel) else []


def load_scenario(name_or_path: str | Path, overrides: list[str] | tuple[str, ...] = ()) -> Scenario:
    """Read a scenario once into a frozen, validated :class:`Scenario`."""
    path = resolve_path(name_or_path)
    source = str(path)
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        raise ScenarioError(f"{source}: not valid YAML: {exc}") from None
    except OSError as exc:
        raise ScenarioError(f"{source}: cannot read: {exc.strerror}") from None
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ScenarioError(f"{source}: top level must be a mapping, got {type(data).__name__}")
    data = apply_overrides(data, list(overrides), source)
    data.setdefault("name", path.stem)
    try:
        return Scenario.model_validate(data)
    except ValidationError as exc:
        raise ScenarioError(_format_validation_error(exc, source)) from None


def scenario_from_dict(data: dict[str, Any], source: str = "<dict>") -> Scenario:
    """Validate an in-memory mapping (tests, gym envs) with the same error format."""
    try:
        return Scenario.model_validate(data)
    except ValidationError as exc:
        raise ScenarioError(_format_validation_error(exc, source)) from None
