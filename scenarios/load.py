"""Load, override and validate scenario files.

Errors name the file, the dotted key path and what is allowed, as a single
:class:`ScenarioError` the CLI prints without a traceback.
"""

from __future__ import annotations

import copy
import difflib
import functools
import json
import re
from importlib import resources
from pathlib import Path
from typing import Any

import yaml
from pydantic import ValidationError

from scenarios.schema import Scenario, without_default_gps_indoors
from scenarios.config.sensor import DEFAULT_ENTRIES, sensor_config_kinds
from scenarios.config.fls import PRESET_KEYS, FlsConfig, FlsPresetName
from scenarios.fls_presets import PRESETS, resolve_geometry
from autonomy.atr.model_file import ModelFileError
from scenarios.sensor_links import atr_sonar_name, sensor_link_problems
from scenarios.comms_checks import comms_problems
from scenarios.mission_limits import mission_limit_problems
from scenarios.placement import placement_problems
from scenarios.timing_checks import timing_problems


class ScenarioError(ValueError):
    """A scenario could not be loaded; the message says where and why."""


class _UniqueKeyLoader(yaml.SafeLoader):
    """YAML safe loader that rejects a key repeated in one mapping (YAML itself keeps the last)."""

    def construct_mapping(self, node, deep=False):  # noqa: ANN001 - PyYAML's signature
        seen: dict = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"key {key!r} appears twice in one mapping (lines {seen[key] + 1} and "
                    f"{key_node.start_mark.line + 1})", key_node.start_mark)
            seen[key] = key_node.start_mark.line
        return super().construct_mapping(node, deep=deep)


# YAML 1.1 (PyYAML) reads 1e12 and 5e-3 as strings (its floats need a dot); read them as numbers.
_UniqueKeyLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"),
)


def _yaml_load(text: str) -> Any:
    return yaml.load(text, Loader=_UniqueKeyLoader)  # noqa: S506 - a SafeLoader subclass


def _validate(data: dict[str, Any], source: str, overrides: list[str] | tuple[str, ...] = ()) -> Scenario:
    """Validate strictly: no coercion of booleans to numbers or strings to numbers/booleans.

    Runs through pydantic's JSON mode so YAML lists fill tuple fields. An indoor scenario
    gets no default GPS (:func:`scenarios.schema.without_default_gps_indoors`).
    """
    data = without_default_gps_indoors(data)
    try:
        text = json.dumps(data, allow_nan=True)
    except (TypeError, ValueError) as exc:
        raise ScenarioError(f"{source}: unsupported value type in the scenario ({exc}); use numbers, strings, "
                            "booleans, lists and mappings") from None
    try:
        return Scenario.model_validate_json(text, strict=True)
    except ValidationError as exc:
        raise ScenarioError(_format_validation_error(exc, source, overrides, data)) from None


def scenario_yaml(scenario: Scenario) -> str:
    """``scenario`` fully resolved as YAML that :func:`load_scenario` reads back to an equal
    scenario: every field, and ``null`` for each default sensor entry the scenario removed
    (left out, the default suite would add it again)."""
    data = scenario.model_dump(mode="json")
    sensors = data.get("sensors") or {}
    for name in DEFAULT_ENTRIES:
        sensors.setdefault(name, None)
    data["sensors"] = sensors
    return yaml.safe_dump(data, sort_keys=False)


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
    """A shipped scenario name (``cssn_lawnmower``) or a path to a YAML file.

    Raises:
        ScenarioError: the path does not exist or is a folder, or the name is not shipped.
    """
    text = str(name_or_path)
    if not text.strip():
        raise ScenarioError("scenario: must be a shipped scenario name or a YAML file path, got an empty string")
    p = Path(text).expanduser()
    if p.is_dir():
        raise ScenarioError(f"{p}: is a directory; give a scenario YAML file or a shipped scenario name")
    if p.suffix in (".yaml", ".yml") or p.exists() or "/" in text or "\\" in text:
        if not p.is_file():
            shipped = p.stem if (scenarios_dir() / f"{p.stem}.yaml").is_file() else None
            hint = f" (the shipped scenario of that name runs as: {shipped})" if shipped else ""
            raise ScenarioError(f"{p}: scenario file not found{hint}")
        return p
    shipped = scenarios_dir() / f"{text}.yaml"
    if not shipped.is_file():
        known = list(list_scenarios())
        close = difflib.get_close_matches(text, known, n=1)
        hint = f"; did you mean {close[0]}?" if close else ""
        raise ScenarioError(f"{text}: no such scenario file or shipped scenario{hint} "
                            f"(shipped: {', '.join(known) or 'none'})")
    return shipped


def _parse_override(item: str) -> tuple[list[str], Any]:
    if "=" not in item:
        raise ScenarioError(f"--set {item}: must look like key.path=value (e.g. --set seed=3)")
    key, raw = item.split("=", 1)
    key = key.strip()
    if not key or any(not part for part in key.split(".")):
        raise ScenarioError(f"--set {item}: has an empty key (must look like key.path=value)")
    try:
        value = _yaml_load(raw) if raw.strip() else ""
    except yaml.YAMLError as exc:
        problem = str(getattr(exc, "problem", "") or exc).splitlines()[0]
        raise ScenarioError(f"--set {item}: cannot parse the value {raw!r} as YAML ({problem})") from None
    return key.split("."), value


def _list_index(node: list, part: str, item: str, where: str) -> int:
    if not part.lstrip("-").isdigit():
        raise ScenarioError(f"--set {item}: {where} is a list; use an index 0 to {len(node) - 1}, got {part!r}")
    index = int(part)
    if not 0 <= index < len(node):
        raise ScenarioError(f"--set {item}: {where} has {len(node)} entr{'y' if len(node) == 1 else 'ies'} "
                            f"(index 0 to {len(node) - 1}), got index {index}")
    return index


def apply_overrides(data: dict[str, Any], overrides: list[str] | tuple[str, ...]) -> dict[str, Any]:
    """Apply ``key.path=value`` overrides (values parsed as YAML) to a raw mapping.

    Raises:
        ScenarioError: an override is malformed, indexes past a list, or goes through a
            value that is not a mapping; the message names the ``--set`` argument.
    """
    for item in overrides:
        path, value = _parse_override(item)
        node: Any = data
        for i, part in enumerate(path):
            where = ".".join(path[:i]) or "the scenario"
            last = i == len(path) - 1
            if isinstance(node, list):
                index = _list_index(node, part, item, where)
                if last:
                    node[index] = value
                else:
                    node = node[index]
            elif isinstance(node, dict):
                if last:
                    node[part] = value
                else:
                    if node.get(part) is None:
                        node[part] = {}
                    node = node[part]
            else:
                raise ScenarioError(f"--set {item}: {where} is a value ({node!r}), not a mapping or list")
    return data


def _override_for(loc: str, overrides: list[str] | tuple[str, ...]) -> str | None:
    """The ``--set`` item that set the value at dotted ``loc`` (or a key above it), if any."""
    for item in reversed(overrides):
        key = item.split("=", 1)[0].strip()
        if loc == key or loc.startswith(key + ".") or key.startswith(loc + "."):
            return item
    return None


_UNION_TAG = re.compile(r"^(constrained-float|constrained-int|float|int|bool|str|literal\[.*\])$")


def _merged_union_errors(errors: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One error per key for a value that fails every member of a union field (``4.0`` or
    ``'from_swath'``): pydantic reports each member under a tag appended to the key; they
    become one ``value_error`` listing what is allowed."""
    out: list[dict[str, Any]] = []
    groups: dict[tuple, dict[str, Any]] = {}
    for err in errors:
        loc = tuple(err["loc"])
        if len(loc) >= 2 and _UNION_TAG.match(str(loc[-1])):
            base = loc[:-1]
            tag = str(loc[-1])
            allowed = (tag[len("literal["):-1].replace("|", " or ") if tag.startswith("literal[")
                       else "a number" + ("" if "constrained" not in tag else f" ({err['msg'].split('should be ', 1)[-1]})"
                                          if "greater" in err["msg"] or "less" in err["msg"] else ""))
            group = groups.get(base)
            if group is None:
                group = groups[base] = {"loc": base, "type": "value_error", "input": err.get("input"), "allowed": []}
                out.append(group)
            group["allowed"].append(allowed)
        else:
            out.append(err)
    for group in groups.values():
        group["msg"] = "allowed: " + " or ".join(dict.fromkeys(group.pop("allowed")))
    return out


def _format_validation_error(exc: ValidationError, source: str, overrides: list[str] | tuple[str, ...] = (),
                             data: dict[str, Any] | None = None) -> str:
    errors = _merged_union_errors(exc.errors(include_url=False))
    lines = [f"{source}: invalid scenario ({len(errors)} error{'s' if len(errors) != 1 else ''})"]
    for err in errors:
        loc = ".".join(str(p) for p in err["loc"])
        # a check across sections (empty loc) names its keys in its message: credit the --set behind one
        keys = [loc] if loc else re.findall(r"\b[a-z_]+(?:\.[a-z_0-9]+)+\b", err["msg"])
        item = next((i for k in keys if (i := _override_for(k, overrides)) is not None), None)
        src = f" (from --set {item})" if item is not None else ""
        kind = err["type"]
        msg = err["msg"]
        if kind == "extra_forbidden":
            allowed = _allowed_keys(err["loc"][:-1], data)
            close = difflib.get_close_matches(str(err["loc"][-1]), allowed, n=1)
            hint = f" (did you mean {close[0]}?)" if close else ""
            msg = f"unknown key{hint}; allowed keys here: {', '.join(allowed)}" if allowed else "unknown key"
        elif kind == "literal_error":
            msg = msg.replace("Input should be", "allowed values:")
        elif kind == "value_error":
            msg = msg.removeprefix("Value error, ")
        given = err.get("input")
        given_txt = "" if kind in ("extra_forbidden", "missing") or isinstance(given, dict) else f" (got {given!r})"
        if loc:
            lines.append(f"  {loc}{src}: {msg}{given_txt}")
        else:  # the message starts with the keys it is about
            lines.append(f"  {msg}{given_txt}{src}" if keys else f"  (top level): {msg}{given_txt}")
    if len(lines) == 2:  # one error: one line, file then key
        return f"{source}: {lines[1].strip()}"
    return "\n".join(lines)


def _allowed_keys(loc: tuple[Any, ...], data: dict[str, Any] | None = None) -> list[str]:
    """Field names of the model at ``loc`` inside :class:`Scenario` (a ``sensors.<name>``
    entry: the config of its ``kind`` in ``data``, default the entry's name)."""
    import typing

    from pydantic import BaseModel

    model: Any = Scenario
    if len(loc) >= 2 and loc[0] == "sensors":
        entry = ((data or {}).get("sensors") or {}).get(loc[1])
        kind = entry.get("kind", loc[1]) if isinstance(entry, dict) else loc[1]
        model = sensor_config_kinds().get(kind)
        if model is None:
            return []
        loc = loc[2:]
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


def _read_text(path: Path) -> str:
    try:
        raw = path.read_bytes()
    except IsADirectoryError:
        raise ScenarioError(f"{path}: is a directory; give a scenario YAML file") from None
    except OSError as exc:
        raise ScenarioError(f"{path}: cannot read: {exc.strerror or exc}") from None
    if b"\0" in raw:
        raise ScenarioError(f"{path}: is a binary file, not a YAML scenario")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ScenarioError(f"{path}: is not UTF-8 text (byte {exc.start}); a scenario is a YAML text file") from None


def _override_paths(overrides: list[str] | tuple[str, ...]) -> list[list[str]]:
    return [item.split("=", 1)[0].strip().split(".") for item in overrides if "=" in item]


def reset_preset_keys(file_data: dict[str, Any], data: dict[str, Any],
                      overrides: list[str] | tuple[str, ...]) -> list[str]:
    """A preset brings its own defaults: where ``overrides`` change a forward-looking sonar
    entry's ``preset``, drop from ``data`` (the scenario after the overrides, edited in place)
    the :data:`scenarios.config.fls.PRESET_KEYS` the scenario file (``file_data``, before
    them) set for its own preset, so they take the new preset's values. A key the command
    line sets itself (or its whole entry) is kept: an explicitly set key wins.

    Returns:
        one note per entry reset, naming the ``--set``, the keys and both presets.
    """
    from typing import get_args

    file_sensors, sensors = file_data.get("sensors"), data.get("sensors")
    if not isinstance(file_sensors, dict) or not isinstance(sensors, dict):
        return []
    paths = _override_paths(overrides)
    default = FlsConfig.model_fields["preset"].default
    notes = []
    for name, before in file_sensors.items():
        after = sensors.get(name)
        if not (isinstance(before, dict) and isinstance(after, dict)
                and before.get("kind", name) == "fls" and after.get("kind", name) == "fls"):
            continue
        old, new = before.get("preset", default), after.get("preset", default)
        if new == old or new not in get_args(FlsPresetName):
            continue
        reset = [k for k in PRESET_KEYS if k in before and k in after
                 and not any(["sensors", name, k][:len(p)] == p for p in paths)]
        for k in reset:
            del after[k]
        if reset:
            item = _override_for(f"sensors.{name}.preset", overrides)
            them = "them" if len(reset) > 1 else "it"
            notes.append(f"--set {item}: sensors.{name} takes the {new} preset's {', '.join(reset)} (the scenario "
                         f"set {them} for {old}; set {them} on the command line too to keep another value)")
    return notes


def load_scenario(name_or_path: str | Path, overrides: list[str] | tuple[str, ...] = (), *,
                  notes: list[str] | None = None) -> Scenario:
    """Read a scenario once into a frozen, validated :class:`Scenario`.

    An override that changes a forward-looking sonar's ``preset`` resets the file's
    preset-tuned keys of that entry to the new preset's values (:func:`reset_preset_keys`);
    ``notes``, when given, receives a line saying so.

    Raises:
        ScenarioError: the file is missing, a folder, binary, empty or not YAML; an
            override is malformed; a value is out of range or not finite; a placement
            is impossible (see :mod:`scenarios.placement`); or the ATR model file named
            by ``autonomy.atr.model_path`` does not exist.
    """
    path = resolve_path(name_or_path)
    source = f"{path.stem} (shipped scenario)" if path.parent == scenarios_dir() else str(path)
    text = _read_text(path)
    try:
        data = _yaml_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        if "'\\t'" in str(exc):
            raise ScenarioError(f"{source}: not valid YAML{where}: a tab character; indent with spaces") from None
        raise ScenarioError(f"{source}: not valid YAML: {' '.join(str(exc).split())}") from None
    if data is None:
        raise ScenarioError(f"{source}: the file is empty (a scenario needs at least a world, a vehicle "
                            "and a survey; start from a shipped one: auvsim validate cssn_lawnmower)")
    if not isinstance(data, dict):
        raise ScenarioError(f"{source}: top level must be a mapping of keys, got {type(data).__name__}")
    _resolve_seabed_file(data, path.parent)
    file_data = copy.deepcopy(data)
    data = apply_overrides(data, list(overrides))
    preset_notes = reset_preset_keys(file_data, data, overrides)
    entry_notes = _new_sensor_entries(file_data, data, overrides, source)
    if notes is not None:
        notes.extend(preset_notes + entry_notes)
    data.setdefault("name", path.stem)
    scenario = _validate(data, source, overrides)
    check_scenario(scenario, source, overrides)
    return scenario


def _new_sensor_entries(file_data: dict[str, Any], data: dict[str, Any], overrides: list[str] | tuple[str, ...],
                        source: str) -> list[str]:
    """Notes for sensor entries an override created, and a :class:`ScenarioError` for one that
    names no sensor kind (a misspelt entry name, say ``fsl``), with the closest name."""

    before = file_data.get("sensors") or {}
    after = data.get("sensors") or {}
    if not isinstance(before, dict) or not isinstance(after, dict):
        return []
    kinds = sensor_config_kinds()
    out = []
    for name in after:
        if name in before or name in DEFAULT_ENTRIES:
            continue
        entry = after[name]
        item = _override_for(f"sensors.{name}", overrides) or f"sensors.{name}..."
        if isinstance(entry, dict) and "kind" not in entry and name not in kinds:
            known = list(dict.fromkeys([*before, *DEFAULT_ENTRIES, *kinds]))
            close = difflib.get_close_matches(name, known, n=1)
            hint = f"did you mean {close[0]}? " if close else ""
            raise ScenarioError(f"{source}: --set {item}: sensors.{name} is no entry of the scenario and no sensor "
                                f"kind ({hint}entries: {', '.join(k for k in known if k in before or k in DEFAULT_ENTRIES)}; "
                                f"a new entry of another name needs kind: one of {', '.join(sorted(kinds))})")
        if entry is not None:
            kind = entry.get("kind", name) if isinstance(entry, dict) else name
            out.append(f"--set {item}: adds a sensor entry {name} (kind {kind}) the scenario did not have")
    return out


def _resolve_seabed_file(data: dict[str, Any], folder: Path) -> None:
    """Make a relative ``world.seabed.file.path`` relative to the scenario file's folder."""
    try:
        f = data["world"]["seabed"]["file"]
        p = Path(str(f["path"])).expanduser()
    except (KeyError, TypeError):
        return
    if not p.is_absolute():
        f["path"] = str(folder / p)


def _sensor_problems(scenario: Scenario) -> list[str]:
    """Checks a sensor config can only make against its hardware preset (range limits, beam
    counts): the simulator's own geometry resolution, run at load so ``validate`` catches them."""
    problems = []
    for name, cfg in scenario.sensors.root.items():
        if getattr(cfg, "kind", None) != "fls" or not cfg.enabled:
            continue

        try:
            resolve_geometry(cfg)
        except ValueError as exc:
            msg = str(exc)
            problems.append(msg.replace("sensors.fls", f"sensors.{name}", 1) if msg.startswith("sensors.fls")
                            else f"sensors.{name}: {msg}")
    return problems


@functools.lru_cache(maxsize=16)
def _model_fan_hw(path: str, mtime_ns: int, size: int) -> tuple[int, int] | str:
    """The (height, width) fan a CNN model file was trained on, or why it cannot be used
    (cached by the file's identity: loading a scenario should not rebuild the session)."""
    from autonomy.atr.cnn_detector import CnnDetector

    try:
        return CnnDetector(path).fan_hw
    except ModelFileError as exc:
        return str(exc)


def _atr_model_problems(scenario: Scenario) -> list[str]:
    """With the cnn detector: its model file loads, and the ATR's sonar makes fans of the size
    the model was trained on (unless ``autonomy.atr.accept_any_fan_size``)."""
    atr = scenario.autonomy.atr
    if atr.detector != "cnn":
        return []
    from autonomy.atr.build import SHIPPED_MODEL_PATH, model_path

    model = model_path(atr)
    if not model.is_file():
        return [f"autonomy.atr.model_path: {model}: no such file"]
    st = model.stat()
    fan_hw = _model_fan_hw(str(model), st.st_mtime_ns, st.st_size)
    if isinstance(fan_hw, str):
        return [f"autonomy.atr.model_path: {fan_hw}"]

    name = atr_sonar_name(scenario)
    if scenario.autonomy.tracking.enabled or name is None or atr.accept_any_fan_size:
        return []  # the tracker runs its own (contour) detector
    cfg = scenario.sensors[name]
    try:
        w, h = resolve_geometry(cfg).fan_size_px
    except ValueError:
        return []  # reported by the sensor checks
    if (h, w) == fan_hw:
        return []
    mh, mw = fan_hw
    which = "the shipped CNN model" if model == SHIPPED_MODEL_PATH else f"the CNN model {model}"
    makers = [p for p, v in PRESETS.items() if tuple(v.fan_size_px) == (mw, mh)]
    if cfg.fan_size_px is not None:
        key, what = f"sensors.{name}.fan_size_px", f"{w} x {h} px fans"
        fix = f"set fan_size_px: [{mw}, {mh}]" + (
            " (or leave it out)" if tuple(PRESETS[cfg.preset].fan_size_px) == (mw, mh) else "") + ", "
    else:
        key, what, fix = f"sensors.{name}.preset", f"{w} x {h} px fans (preset {cfg.preset})", ""
        if makers:
            fix = f"set preset: {' or '.join(makers)} for a fan the model knows, "
    return [f"{key}: the ATR's sonar makes {what} but {which} was trained on {mw} x {mh} px fans (width x "
            f"height); {fix}use a model trained on this sonar (autonomy.atr.model_path), "
            "autonomy.atr.detector: classical or none, or autonomy.atr.accept_any_fan_size: true to run "
            "this model on the fans resized (its detections there are not validated)"]


def check_scenario(scenario: Scenario, source: str, overrides: list[str] | tuple[str, ...] = ()) -> None:
    """Checks across keys that field validation cannot make: placements, files, and surveys
    that would break the mission's own abort limits (:mod:`scenarios.mission_limits`).

    Raises:
        ScenarioError: listing every problem found, one per line.
    """
    problems = (placement_problems(scenario) + _sensor_problems(scenario) + sensor_link_problems(scenario)
                + _atr_model_problems(scenario) + comms_problems(scenario) + mission_limit_problems(scenario)
                + timing_problems(scenario))
    for k, problem in enumerate(problems):
        for item in overrides:
            parts = item.split("=", 1)[0].strip().split(".")
            prefixes = [".".join(parts[:n]) for n in range(len(parts), 0, -1)]
            if any(problem.startswith((p + ":", p + " (")) or f" and {p} (" in problem or f" {p} (" in problem
                   for p in prefixes[:-1] or prefixes):
                problems[k] = f"{problem} (from --set {item})"
                break
    if problems:
        lines = [f"{source}: impossible scenario ({len(problems)} problem{'s' if len(problems) != 1 else ''})"]
        lines += [f"  {p}" for p in problems]
        raise ScenarioError("\n".join(lines) if len(problems) > 1 else f"{source}: {problems[0]}")


def scenario_from_dict(data: dict[str, Any], source: str = "<dict>") -> Scenario:
    """Validate an in-memory mapping (tests, gym envs) with the same error format."""
    scenario = _validate(data, source)
    check_scenario(scenario, source)
    return scenario
