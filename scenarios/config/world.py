"""World config: seabed, basin walls, targets and water current."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from autonomy.geodesy import GeodeticOrigin
from scenarios.config.movers import MoverConfig
from scenarios.config.base import NonNegFloat, PositiveFloat, Probability, StrictModel, Vec2, Vec3


class BathymetryFileConfig(StrictModel):
    """A measured depth grid read from a file (``world.seabed.kind: file``).

    Formats: a GeoTIFF in a projected CRS in metres (read with rasterio), an ASCII XYZ
    point grid (``easting northing value`` per line, metres, a regular grid), or a NumPy
    ``.npy`` 2-D array (rows northwards from ``origin_ne_m``, columns eastwards, every
    ``spacing_m``). The grid is placed in the mission NED frame by ``origin_en_m``: the
    projected (easting, northing) of the mission origin (GeoTIFF and XYZ).
    """

    path: str = Field(min_length=1, description="file path; relative paths start at the scenario file's folder")
    format: Literal["auto", "geotiff", "xyz", "npy"] = Field("auto", description="auto: from the suffix")
    values: Literal["depth", "elevation"] = Field(
        "depth", description="depth: positive down (m); elevation: positive up, below sea level negative")
    origin_en_m: Vec2 | None = Field(
        None, description="projected (easting, northing) of the mission NED origin, m (GeoTIFF, XYZ)")
    origin_ne_m: Vec2 = Field((0.0, 0.0), description=".npy: NED north/east of cell [0, 0], m")
    spacing_m: PositiveFloat | None = Field(None, le=1000.0, description=".npy: grid spacing, m")
    crop_ne_m: tuple[Vec2, Vec2] | None = Field(
        None, description="keep ((north_min, north_max), (east_min, east_max)) in mission NED, m")
    decimate: int = Field(1, ge=1, le=100, description="keep every n-th grid node")
    nodata: float | None = Field(None, description="value marking missing cells (GeoTIFF: from the file)")


class SeabedConfig(StrictModel):
    """Seabed surface. ``plane`` and ``slope`` are MuJoCo planes; ``rough``, ``ripple`` and
    ``file`` (a measured grid, :class:`BathymetryFileConfig`) are trimesh triangle meshes
    (never height fields: their ray casts are ~10x slower)."""

    kind: Literal["plane", "slope", "rough", "ripple", "file"] = "plane"
    depth_m: PositiveFloat = Field(
        4.0, le=11000.0, description="depth (m) of the mean seabed surface at center_ne_m, the patch centre "
        "(a slope passes through it; elsewhere the depth follows the slope)")
    slope_deg: float = Field(0.0, ge=0.0, lt=45.0)
    slope_azimuth_deg: float = Field(0.0, ge=-360.0, le=360.0, description="downhill direction")
    roughness_m: NonNegFloat = Field(0.05, le=5.0, description="rms height of rough seabed")
    roughness_corr_m: PositiveFloat = Field(2.0, description="correlation length of roughness")
    ripple_amplitude_m: NonNegFloat = Field(0.05, le=2.0)
    ripple_wavelength_m: PositiveFloat = 1.0
    ripple_azimuth_deg: float = Field(0.0, ge=-360.0, le=360.0)
    extent_m: PositiveFloat = Field(120.0, le=5000.0, description="side of the square patch")
    center_ne_m: Vec2 = Field((0.0, 0.0), description="north/east centre (m) of the patch, where the depth is depth_m")
    mesh_resolution_m: PositiveFloat = Field(0.5, ge=0.05, le=10.0)
    reflectivity: Probability = 0.3
    file: BathymetryFileConfig | None = Field(None, description="the depth grid of kind: file")

    @model_validator(mode="after")
    def _file_given(self) -> "SeabedConfig":
        if (self.kind == "file") != (self.file is not None):
            raise ValueError("world.seabed.file is required with kind: file and only allowed with it")
        return self


class BasinConfig(StrictModel):
    """Optional vertical walls from the surface to the seabed."""

    shape: Literal["none", "rectangular", "circular"] = "none"
    center_ne_m: Vec2 = (0.0, 0.0)
    size_ne_m: tuple[PositiveFloat, PositiveFloat] = (60.0, 60.0)
    radius_m: PositiveFloat = 30.0
    wall_thickness_m: PositiveFloat = 0.3
    reflectivity: Probability = 0.8


TargetShape = Literal["half_sphere", "truncated_cone", "cylinder", "box", "tyre", "bottle", "can", "chain",
                      "drink_carton", "hook", "propeller", "shampoo_bottle", "valve"]
#: Marine-debris shapes (:mod:`sim.scene.debris_meshes`): sized by ``size_m`` (length, width, height).
DEBRIS_TARGET_SHAPES = ("bottle", "can", "chain", "drink_carton", "hook", "propeller", "shampoo_bottle", "valve")
#: Default (length, width, height) of each debris shape lying in its default pose, m: an estimate
#: of a common real object (:mod:`sim.scene.debris_meshes` builds them to this box).
DEBRIS_DEFAULT_SIZES_M: dict[str, tuple[float, float, float]] = {
    "bottle": (0.25, 0.08, 0.08), "can": (0.12, 0.066, 0.066), "chain": (0.45, 0.052, 0.052),
    "drink_carton": (0.2, 0.095, 0.07), "hook": (0.15, 0.08, 0.012), "propeller": (0.24, 0.266, 0.06),
    "shampoo_bottle": (0.2, 0.08, 0.045), "valve": (0.2, 0.1, 0.12)}
BOX_DEFAULT_SIZE_M = (1.0, 0.5, 0.5)


class TargetConfig(StrictModel):
    """A seabed object built from a closed mesh (:mod:`sim.scene.target_meshes`). ``pos_ned`` is
    the centre of its base; its z is the depth of the base (use the seabed depth to lay it on a
    flat bottom).

    Shapes: ``half_sphere`` (``radius_m``), ``truncated_cone`` (``radius_m`` at the base,
    ``top_radius_m``, ``height_m``), ``cylinder`` (upright: ``radius_m``, ``height_m``), ``box``
    (``size_m``), ``tyre`` (a torus lying flat: outer ``radius_m``, ``tube_radius_m``), and the
    marine debris of the real water-tank sonar set (:mod:`sim.scene.debris_meshes`, whose
    docstring tables their default sizes, ``debris_default_size_m``), each scaled so that its box
    in the default pose is exactly ``size_m`` (length along x, width along y, height):

    * ``bottle``: a drink bottle (body, shoulder, neck, cap), lying along x, base end at -x;
      stand it up with ``rpy_deg: [0, 90, yaw]`` and ``pos_ned`` half its length above the
      bottom (its base end then rests on it);
    * ``can``: a drink can with its rims, lying along x;
    * ``chain``: a row of interlinked oval links along x, alternate links on edge;
    * ``drink_carton``: a brick carton with its top seal and cap, lying on its broad face;
    * ``hook``: a J-bent round bar with an eye on its shank, lying flat;
    * ``propeller``: a hub and three twisted blades, lying flat on its hub;
    * ``shampoo_bottle``: a bottle of flattened (elliptical) section with a cap, lying flat;
    * ``valve``: a flanged gate valve on its flanges, stem and hand-wheel on top.
    """

    name: str = Field(min_length=1)
    shape: TargetShape
    pos_ned: Vec3
    rpy_deg: Vec3 = (0.0, 0.0, 0.0)
    radius_m: PositiveFloat = Field(0.5, le=20.0, description="sphere/cylinder/cone base/tyre")
    top_radius_m: NonNegFloat = Field(0.2, le=20.0, description="truncated cone top radius")
    height_m: PositiveFloat = Field(0.5, le=20.0, description="cylinder/cone height")
    size_m: tuple[PositiveFloat, PositiveFloat, PositiveFloat] = Field(
        BOX_DEFAULT_SIZE_M, description="box, and debris shapes: (length, width, height), m (left out: "
        "(1.0, 0.5, 0.5) for a box, DEBRIS_DEFAULT_SIZES_M for a debris shape)")
    tube_radius_m: PositiveFloat = Field(0.15, le=5.0, description="tyre tube radius")
    reflectivity: Probability = 0.9
    class_name: str = "opi"
    is_target: bool = True

    @model_validator(mode="after")
    def _debris_size(self) -> "TargetConfig":
        # an after-validator: a before one would turn the strict JSON validation of a scenario
        # file into Python validation, where a list is not a tuple
        if "size_m" not in self.model_fields_set and self.shape in DEBRIS_DEFAULT_SIZES_M:
            object.__setattr__(self, "size_m", DEBRIS_DEFAULT_SIZES_M[self.shape])  # the model is frozen
        return self

    @model_validator(mode="after")
    def _tyre_fits(self) -> "TargetConfig":
        if self.shape == "tyre" and self.tube_radius_m >= self.radius_m:
            raise ValueError("tyre needs tube_radius_m < radius_m")
        return self


class CurrentConfig(StrictModel):
    """Ocean current: constant plus first-order Gauss-Markov, NED m/s."""

    velocity_ned_mps: Vec3 = (0.0, 0.0, 0.0)
    gauss_markov_sigma_mps: NonNegFloat = Field(0.0, le=5.0)
    gauss_markov_tau_s: PositiveFloat = 60.0


class WorldConfig(StrictModel):
    """The scene: seabed, walls, targets, movers, current, and where on Earth the mission NED
    frame sits (``origin``: latitude, longitude, ellipsoidal height; default the CSSN basin,
    La Spezia; :mod:`autonomy.geodesy`).

    ``indoor: true`` is a roofed pool or tank: no sky view, so no satellite fix. Such a
    scenario has no GPS: the default suite leaves it out and an enabled ``gps`` entry is
    refused at load (:class:`scenarios.schema.Scenario`).
    """

    origin: GeodeticOrigin = Field(GeodeticOrigin(), description="WGS-84 origin of the mission NED frame")
    seabed: SeabedConfig = SeabedConfig()
    basin: BasinConfig = BasinConfig()
    indoor: bool = Field(False, description="a roofed pool or tank: no sky view, so no GPS (the default suite "
                         "leaves it out; an enabled gps entry is refused)")
    targets: tuple[TargetConfig, ...] = ()
    movers: tuple[MoverConfig, ...] = Field((), description="moving targets on mocap bodies (diver, vehicle)")
    current: CurrentConfig = CurrentConfig()

    @model_validator(mode="after")
    def _unique_names(self) -> "WorldConfig":
        names = [t.name for t in self.targets] + [m.name for m in self.movers]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise ValueError(f"target names must be unique, repeated: {sorted(dup)}")
        return self
