"""Dataset specs: the sonar, the scenes, the objects and the label formats of a labelled
synthetic dataset, in one YAML file validated like a scenario (``auvsim dataset --spec``).

A spec names its scenes' kind:

===========  ===================================================================================
``kind``     scenes
===========  ===================================================================================
``seabed``   the open-seabed forward-looking scenes of the survey ATR (mine-like targets, rocks,
             debris on randomised seabeds; :class:`sim.dataset.randomization.Randomization`):
             ``randomization`` names a preset (``train``, ``wide``, ``heldout``) and ``ranges``
             changes any of its fields; frames on the sonar's own fan image
``tank``     a water tank seen from above (:mod:`sim.dataset.tank_scenes`): a flat floor, one
             to ``objects`` objects of the ``catalogue`` (class, debris shape, pitch, weight),
             a wall across the far fan in ``wall_share`` of the scenes (class ``Wall``); frames
             resampled onto ``image``'s fan pixel grid (a real sonar's exported frames)
===========  ===================================================================================

``sonar`` gives the preset and any further forward-looking sonar setting (gain, TVG, image
formation: :class:`scenarios.config.fls.FlsConfig`'s keys, checked against it); ``labels`` when
an object counts as ``iscrowd`` (too little of it seen); ``formats`` what is written besides
the COCO file (``yolo`` label files, ``watertank`` box files and class masks: the layout of
the Marine Debris set, [MarineDebrisFLS]). Shipped specs (``sim/dataset/specs/*.yaml``) are
named by their file stem: ``fls_train``, ``fls_wide``, ``fls_heldout`` (the survey ATR's sets)
and ``marine_debris_watertank`` (the ARIS 3000 tank frames of the Marine Debris set).
"""

from __future__ import annotations

import difflib
import math
import re
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
import yaml
from pydantic import Field, ValidationError, field_validator, model_validator

from autonomy.sonar_geometry import FanGeometry
from scenarios.config.base import StrictModel
from scenarios.config.fls import FlsConfig, FlsPresetName
from scenarios.config.sonar_formation import SonarFormationConfig
from scenarios.config.world import DEBRIS_TARGET_SHAPES
from scenarios.fls_presets import resolve_geometry
from sim.dataset.errors import DatasetError
from sim.dataset.randomization import RANDOMIZATION_PRESETS, Randomization

SPECS_DIR = Path(__file__).resolve().parent / "specs"
Range = tuple[float, float]
FORMATS = ("coco", "yolo", "watertank")
#: The fields a spec's ``sonar`` sets itself (not through ``settings``).
SONAR_OWN_KEYS = ("preset", "elevation_rays", "azimuth_columns")


def _ordered(name: str, r: tuple) -> None:
    if r[0] > r[1]:
        raise ValueError(f"{name}: lower bound {r[0]} above upper bound {r[1]}")


class SonarSpec(StrictModel):
    """The forward-looking sonar every frame is rendered with."""

    preset: FlsPresetName = "m900_130"
    elevation_rays: int | None = Field(None, ge=1, le=256, description="None: the sonar config's default")
    azimuth_columns: int | None = Field(None, ge=8, le=4096, description="None: the preset's beams")
    settings: dict[str, Any] = Field(default_factory=dict, description="further FlsConfig keys")
    randomize: dict[str, tuple[float, float]] = Field(
        default_factory=dict, description="FlsConfig keys (formation.KEY for the image formation's) drawn per "
                                          "scene, uniformly in [low, high] (integers for integer keys)")

    @field_validator("randomize", mode="before")
    @classmethod
    def _randomize_as_written(cls, value: Any) -> Any:
        return _randomize_pairs(value)

    def fls_fields(self, drawn: dict[str, float] | None = None) -> dict[str, Any]:
        """The :class:`FlsConfig` fields the spec sets (besides the scenes' tilt and window),
        with ``drawn`` (values of :attr:`randomize`'s keys, :meth:`draw`) in place of
        ``settings``' where given."""
        own = {k: getattr(self, k) for k in ("elevation_rays", "azimuth_columns") if getattr(self, k) is not None}
        out = {"preset": self.preset, **own, **self.settings}
        for key, value in (drawn or {}).items():
            head, _, sub = key.partition(".")
            if sub:
                out[head] = {**out.get(head, {}), sub: value}
            else:
                out[key] = value
        return out

    def draw(self, rng: np.random.Generator) -> dict[str, float]:
        """One scene's values of :attr:`randomize`, in its key order: uniform in each range,
        integers (inclusive) for integer keys. Empty (no draw) without ``randomize``."""
        out: dict[str, float] = {}
        for key, (lo, hi) in self.randomize.items():
            out[key] = int(rng.integers(int(lo), int(hi) + 1)) if _is_int_key(key) else float(rng.uniform(lo, hi))
        return out

    @model_validator(mode="after")
    def _settings_are_fls_keys(self) -> "SonarSpec":
        own = sorted(set(self.settings) & set(SONAR_OWN_KEYS) | set(self.settings) & {"tilt_deg", "range_window_m"})
        if own:
            raise ValueError(f"settings: {', '.join(own)} set by the spec itself (sonar.{own[0]} or the scenes), "
                             "not under settings")
        try:
            cfg = FlsConfig(**self.fls_fields())
        except ValidationError as exc:
            err = exc.errors(include_url=False)[0]
            loc = ".".join(str(p) for p in err["loc"])
            msg = err["msg"]
            if err["type"] == "extra_forbidden":
                msg = _unknown_key_message(err["loc"])
            raise ValueError(f"settings.{loc}: {msg}") from None
        try:
            resolve_geometry(cfg)
        except ValueError as exc:
            raise ValueError(str(exc).replace("sensors.fls.", "sonar.")) from None
        for key, (lo, hi) in self.randomize.items():
            _check_randomized_key(self, key, lo, hi)
        return self


#: Sonar keys a tank frame's renderer or the spec sets itself, never drawn per scene.
NOT_RANDOMIZED = SONAR_OWN_KEYS + ("tilt_deg", "range_window_m", "range_min_m", "range_max_m", "rate_hz",
                                   "latency_s", "mount_site", "kind", "formation")
_NUMERIC = (float, int, float | None, int | None)


def _randomize_pairs(value: Any) -> Any:
    """``sonar.randomize`` as written, checked before typing: a mapping of ``KEY: [low, high]``
    (numbers, not booleans); ``formation: {KEY: [low, high]}`` is read as ``formation.KEY``."""
    if not isinstance(value, dict):
        raise ValueError(f"a mapping of setting: [low, high], got {type(value).__name__}")
    out: dict[str, Any] = {}
    for key, pair in value.items():
        if key == "formation" and isinstance(pair, dict):
            out.update({f"formation.{k}": v for k, v in pair.items()})
        else:
            out[str(key)] = pair
    for key, pair in out.items():
        if (not isinstance(pair, (list, tuple)) or len(pair) != 2
                or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in pair)):
            raise ValueError(f"{key}: a [low, high] pair of numbers, got {pair!r}")
    return out


def _check_randomized_key(sonar: "SonarSpec", key: str, lo: float, hi: float) -> None:
    """Refuse (one line) a ``randomize`` key that is not a numeric sonar setting drawn per
    scene, or bounds that are not one (each bound is built into an :class:`FlsConfig`)."""
    if key in NOT_RANDOMIZED:
        why = ("give its keys one by one, formation.KEY: [low, high]" if key == "formation" else
               "drawn per scene by scene.tilt_deg" if key == "tilt_deg" else
               "set by the image grid (image.near_m, image.far_m)" if key.startswith("range_") else
               f"set once for all frames by sonar.{key}" if key in SONAR_OWN_KEYS else
               "no effect on a still tank frame")
        raise ValueError(f"randomize.{key}: not drawn per scene: {why}")
    field = _randomized_field(key)
    if field is None:
        name = key.partition(".")[2] or key
        names = [f"formation.{k}" for k in SonarFormationConfig.model_fields] + [
            k for k in FlsConfig.model_fields if k not in NOT_RANDOMIZED]
        close = difflib.get_close_matches(key, names, n=1, cutoff=0.6) or difflib.get_close_matches(
            f"formation.{name}", names, n=1, cutoff=0.8)
        hint = f"; did you mean {close[0]}?" if close else ""
        raise ValueError(f"randomize.{key}: not a forward-looking sonar setting (KEY, or formation.KEY for the "
                         f"image formation; the keys are listed in docs/cli.md){hint}")
    if field.annotation not in _NUMERIC:
        raise ValueError(f"randomize.{key}: not a numeric setting (a switch or a choice); set it under "
                         "sonar.settings instead")
    _ordered(f"randomize.{key}", (lo, hi))
    if _is_int_key(key) and (lo != int(lo) or hi != int(hi)):
        raise ValueError(f"randomize.{key}: an integer setting; give whole-number bounds, got {[lo, hi]}")
    for bound in (lo, hi):
        value = int(bound) if _is_int_key(key) else float(bound)
        try:
            FlsConfig(**sonar.fls_fields({key: value}))
        except ValidationError as exc:
            err = exc.errors(include_url=False)[0]
            raise ValueError(f"randomize.{key}: bound {bound}: {err['msg']}") from None


def _randomized_field(key: str):
    """The pydantic field a ``randomize`` key names (``KEY`` of :class:`FlsConfig`,
    ``formation.KEY`` of :class:`SonarFormationConfig`), or None."""
    head, _, sub = key.partition(".")
    if not sub:
        return FlsConfig.model_fields.get(head)
    return SonarFormationConfig.model_fields.get(sub) if head == "formation" else None


def _is_int_key(key: str) -> bool:
    """Whether a ``randomize`` key names an integer setting."""
    return _randomized_field(key).annotation in (int, int | None)


def _unknown_key_message(loc: tuple) -> str:
    """'not a ... setting' for an unknown key at ``loc`` (in the sonar's settings or in its
    ``formation``), with the closest known key and where the keys are listed."""
    in_formation = len(loc) > 1 and loc[0] == "formation"
    known = SonarFormationConfig.model_fields if in_formation else FlsConfig.model_fields
    close = difflib.get_close_matches(str(loc[-1]), list(known), n=1, cutoff=0.6)
    what = "an image-formation setting" if in_formation else "a forward-looking sonar setting"
    hint = f"; did you mean {close[0]}?" if close else ""
    return f"not {what}{hint} (the keys are listed in docs/cli.md)"


class LabelRules(StrictModel):
    """An object below either bound is labelled ``iscrowd`` (present, not expected to be found)."""

    min_visible_fraction: float = Field(0.3, ge=0.0, le=1.0)
    min_area_px: int = Field(12, ge=0)


class SeabedScenes(StrictModel):
    """Open-seabed scenes: a randomisation preset, some of its ranges changed."""

    kind: Literal["seabed"]
    randomization: Literal["train", "wide", "heldout"] = "train"
    ranges: dict[str, Any] = Field(default_factory=dict, description="Randomization fields replaced")

    def build(self):
        """The :class:`sim.dataset.randomization.Randomization` the scenes are drawn from.

        Raises:
            ValueError: a field of ``ranges`` that is not a randomisation range, or out of range.
        """
        base = RANDOMIZATION_PRESETS[self.randomization]
        if not self.ranges:
            return base
        try:
            return Randomization.model_validate({**base.model_dump(), **self.ranges})
        except ValidationError as exc:
            err = exc.errors(include_url=False)[0]
            loc = ".".join(str(p) for p in err["loc"])
            msg = err["msg"].replace("Extra inputs are not permitted", "not a randomisation range")
            raise ValueError(f"ranges{'.' + loc if loc else ''}: {msg.removeprefix('Value error, ')}") from None

    @model_validator(mode="after")
    def _ranges_valid(self) -> "SeabedScenes":
        self.build()
        return self


class CatalogueItem(StrictModel):
    """One kind of object of a tank scene."""

    class_name: str = Field(min_length=1)
    shape: Literal[DEBRIS_TARGET_SHAPES + ("tyre",)]  # type: ignore[valid-type]
    pitch_deg: float = Field(0.0, ge=-90.0, le=90.0, description="90: stood up on its base")
    weight: float = Field(1.0, gt=0.0, description="share of the objects drawn")
    size_scale: Range = Field((0.85, 1.15), description="factor on the shape's default size, drawn per object")

    @model_validator(mode="after")
    def _scale(self) -> "CatalogueItem":
        _ordered("size_scale", self.size_scale)
        if not (0.05 <= self.size_scale[0] and self.size_scale[1] <= 20.0):
            raise ValueError(f"size_scale: allowed within [0.05, 20], got {list(self.size_scale)}")
        return self


class TankScenes(StrictModel):
    """A water tank seen from above (:class:`sim.dataset.tank_scenes.TankGeometry`)."""

    kind: Literal["tank"]
    floor_depth_m: float = Field(3.0, gt=0.0, le=50.0)
    height_m: Range = (0.25, 0.42)
    tilt_deg: Range = (12.0, 20.0)
    wall_share: float = Field(0.5, ge=0.0, le=1.0)
    wall_range_m: Range = (2.2, 3.2)
    objects: tuple[int, int] = (1, 3)
    object_range_m: Range = (1.0, 2.6)
    floor_reflectivity: float = Field(0.3, gt=0.0, le=1.0)
    wall_reflectivity: float = Field(0.6, gt=0.0, le=1.0)
    gain_jitter_db: float = Field(3.0, ge=0.0, le=20.0)
    frames_per_scene: int = Field(1, ge=1, le=100)
    catalogue: list[CatalogueItem] = Field(min_length=1)

    @model_validator(mode="after")
    def _check(self) -> "TankScenes":
        for name in ("height_m", "tilt_deg", "wall_range_m", "objects", "object_range_m"):
            _ordered(name, getattr(self, name))
        if self.objects[0] < 0:
            raise ValueError(f"objects: at least 0 objects, got {self.objects[0]}")
        names = [c.class_name for c in self.catalogue]
        if len(set(names)) < len(names) and len({(c.class_name, c.shape, c.pitch_deg) for c in self.catalogue}) < len(names):
            raise ValueError("catalogue: the same class, shape and pitch listed twice")
        if "Wall" in names:
            raise ValueError("catalogue: Wall is the tank's own wall (wall_share), not an object to list")
        if not 0.0 < self.height_m[0] < self.floor_depth_m:
            raise ValueError(f"height_m: the sonar must be above the floor and below the surface "
                             f"(0 < height < floor_depth_m {self.floor_depth_m}), got {self.height_m}")
        return self

    def class_names(self) -> tuple[str, ...]:
        """Labelled classes: the catalogue's, in order of first listing, then ``Wall`` when
        scenes may have one."""
        names = tuple(dict.fromkeys(c.class_name for c in self.catalogue))
        return names + (("Wall",) if self.wall_share > 0.0 else ())


class FanGrid(StrictModel):
    """The fan pixel grid tank frames are written on (a real sonar's exported frames): image
    size, the apex (the sonar; it may lie below the image), the field of view, the range
    window and the metres per pixel (isotropic)."""

    width_px: int = Field(ge=16, le=8192)
    height_px: int = Field(ge=16, le=8192)
    apex_x_px: float
    apex_y_px: float
    fov_deg: float = Field(gt=1.0, lt=180.0)
    near_m: float = Field(gt=0.0)
    far_m: float = Field(gt=0.0)
    m_per_px: float = Field(gt=0.0)

    @model_validator(mode="after")
    def _check(self) -> "FanGrid":
        if not self.far_m > self.near_m:
            raise ValueError(f"far_m: must exceed near_m ({self.near_m}), got {self.far_m}")
        top = self.apex_y_px - self.far_m / self.m_per_px
        if top < -1.0:
            raise ValueError(f"far_m: the far arc ({self.far_m / self.m_per_px:.1f} px from the apex) lies above "
                             f"the image (its top at row {top:.1f}); check far_m, m_per_px and apex_y_px")
        return self

    def geometry(self):
        """The grid as a :class:`autonomy.sonar_geometry.FanGeometry`."""
        return FanGeometry(self.width_px, self.height_px, self.near_m, self.far_m, math.radians(self.fov_deg),
                           self.m_per_px, self.apex_x_px, self.apex_y_px)


class DatasetSpec(StrictModel):
    """A labelled synthetic dataset (module docstring)."""

    name: str = Field(min_length=1)
    description: str = ""
    sensor: Literal["fls"] = "fls"
    scene: Annotated[SeabedScenes | TankScenes, Field(discriminator="kind")]
    sonar: SonarSpec = SonarSpec()
    image: FanGrid | None = None
    labels: LabelRules = LabelRules()
    formats: tuple[Literal["coco", "yolo", "watertank"], ...] = ("coco", "yolo")

    @model_validator(mode="after")
    def _check(self) -> "DatasetSpec":
        if "coco" not in self.formats:
            raise ValueError("formats: coco is always written (it is the dataset's index); list it")
        if len(set(self.formats)) < len(self.formats):
            raise ValueError(f"formats: listed twice in {list(self.formats)}")
        if self.scene.kind == "tank" and self.image is None:
            raise ValueError("image: a tank spec needs the fan pixel grid its frames are written on")
        if self.scene.kind == "tank":
            sc, im = self.scene, self.image
            far_ground = math.sqrt(max(im.far_m**2 - sc.height_m[0] ** 2, 0.0))
            if sc.object_range_m[1] > far_ground:
                raise ValueError(f"scene.object_range_m: objects up to {sc.object_range_m[1]} m ground range lie "
                                 f"beyond the window (far_m {im.far_m} m: {far_ground:.2f} m on the floor from "
                                 f"the lowest sonar); frames would miss them")
            if sc.height_m[1] >= im.far_m:
                raise ValueError(f"scene.height_m: a sonar {sc.height_m[1]} m above the floor sees no floor within "
                                 f"the window (far_m {im.far_m} m)")
        if self.scene.kind == "seabed" and self.image is not None:
            raise ValueError("image: seabed frames are written on the sonar's own fan image; leave image out")
        if self.scene.kind == "seabed" and set(self.formats) != {"coco", "yolo"}:
            raise ValueError(f"formats: seabed datasets write coco and yolo (watertank box files are for tank "
                             f"scenes), got {list(self.formats)}")
        if self.scene.kind == "seabed" and self.sonar.randomize:
            raise ValueError("sonar.randomize: seabed scenes randomise gain, noise and speckle themselves "
                             "(scene.ranges); randomize is for tank scenes")
        if self.scene.kind == "seabed" and self.sonar.settings:
            raise ValueError("sonar.settings: seabed scenes randomise gain, noise and speckle themselves "
                             "(scene.ranges); leave settings out")
        return self


def shipped_specs() -> tuple[str, ...]:
    """Names of the shipped specs (file stems in ``sim/dataset/specs/``)."""
    return tuple(sorted(p.stem for p in SPECS_DIR.glob("*.yaml")))


def load_spec(name_or_path: str | Path, arg: str = "--spec") -> DatasetSpec:
    """A spec by shipped name or YAML path.

    Raises:
        DatasetError: no such spec, unreadable YAML, or an invalid spec: one line naming the
            file, the dotted key and what is allowed.
    """
    text = str(name_or_path)
    path = Path(text).expanduser()
    if path.is_dir():
        raise DatasetError(f"{arg} {text}: is a folder; name a spec file (.yaml) or a shipped spec "
                           f"({', '.join(shipped_specs())})")
    if not path.is_file():
        shipped = SPECS_DIR / f"{text}.yaml"
        if "/" in text or text.endswith((".yaml", ".yml")) or not shipped.is_file():
            close = difflib.get_close_matches(Path(text).stem, shipped_specs(), n=1)
            hint = f"; did you mean {close[0]}?" if close else ""
            raise DatasetError(f"{arg} {text}: no such file, and no shipped spec of that name (shipped: "
                               f"{', '.join(shipped_specs())}){hint}")
        path = shipped
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f", line {mark.line + 1}" if mark is not None else ""
        what = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise DatasetError(f"{arg} {path}: not a readable YAML file ({what}{where})") from None
    if not isinstance(data, dict):
        raise DatasetError(f"{arg} {path}: a spec is a YAML mapping (name, scene, sonar, ...), got "
                           f"{type(data).__name__}")
    try:
        return DatasetSpec.model_validate(data)
    except ValidationError as exc:
        err = exc.errors(include_url=False)[0]
        loc = ".".join(str(p) for p in err["loc"] if not (isinstance(p, str) and p in ("seabed", "tank")))
        msg = err["msg"].removeprefix("Value error, ")
        given = err.get("input")
        key = re.match(r"([a-z_][a-z_0-9.]*): ", msg) if err["type"] == "value_error" else None
        if key:  # a check of a section names the key it is about: one dotted path
            loc, msg = ".".join(filter(None, (loc, key.group(1)))), msg[key.end():]
        if err["type"] == "extra_forbidden":
            msg = "unknown key"
        elif err["type"] == "literal_error":
            msg = msg.replace("Input should be", "allowed values:")
        elif err["type"] in ("tuple_type", "too_short", "too_long") and isinstance(given, (int, float, list)):
            msg = "a [low, high] pair of numbers"
        elif err["type"] == "union_tag_invalid":
            msg = f"allowed values: {err.get('ctx', {}).get('expected_tags', 'seabed, tank')}"
            shown_tag = err.get("ctx", {}).get("tag")
            given = shown_tag if shown_tag is not None else given
        shown = "" if err["type"] in ("extra_forbidden", "missing") or isinstance(given, (dict, list)) \
            else f" (got {given!r})"
        more = len(exc.errors()) - 1
        raise DatasetError(f"{arg} {path}: {loc + ': ' if loc else ''}{msg}{shown}"
                           + (f" (and {more} more)" if more > 0 else "")) from None

