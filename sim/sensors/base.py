"""The one sensor contract: name, kind, rate, latency, mount, reset and measure.

Every simulated sensor derives from :class:`Sensor` and registers by kind
(:func:`sim.sensors.registry.register_sensor`). The scheduler owns timing: a sensor keeps no
clock, it is asked to ``measure(truth, scene)`` when it is due, and its message is delivered
``latency_s(msg)`` later.

As dm_control's observables, the ideal value is kept apart from its corruption:
``ideal(truth, scene)`` computes what a perfect instrument would report (or the exact
physical quantities the corruption needs), ``corrupt`` adds noise, biases and dropouts drawn
from the sensor's own generator, and ``exact`` forms the noise-free message. ``measure(...,
noise=False)`` therefore returns exact values and draws nothing. :meth:`Sensor.measure` is
the template and no sensor overrides it: a sensor implements ``ideal`` (and ``corrupt`` /
``exact`` where its noise-free output is not yet the message). Sensors whose noise enters
mid-way through a rendering (the sonars: speckle on the noise-free echo intensities) return
from ``ideal`` everything up to the first draw, so that ``corrupt`` draws in the order the
whole render did.

What a caller may ask of a sensor without probing its attributes is declared on its class:
:attr:`Sensor.ground_truth_optional` (it can skip computing its ground truth: set
:attr:`Sensor.render_truth`) and :attr:`Sensor.fixed_latency` (its delivery delay does not
depend on the message).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar, Generic, Protocol, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.frames import rot_from_euler
from scenarios.config.sensor import SensorConfig
from sim.sensors.raycast import RayCaster
from sim.dynamics.truth import VehicleTruth

FloatArray = NDArray[np.float64]
MsgT = TypeVar("MsgT")


class SceneObjectLike(Protocol):
    """A labelled scene object as sensors see it (``sim.scene.world.SceneObject`` fits)."""

    id: int
    name: str
    class_name: str
    is_target: bool
    centroid_ned: FloatArray


@dataclass(frozen=True)
class SceneView:
    """What a sensor may look at, at capture time ``t_s``.

    Attributes:
        t_s: capture time, s.
        caster: ray caster over the scene's acoustic geometry.
        objects: the labelled scene objects with their poses at ``t_s`` (moving bodies
            included), for ground truth.
    """

    t_s: float
    caster: RayCaster | None
    objects: Sequence[SceneObjectLike] = ()

    def require_caster(self, who: str) -> RayCaster:
        """The ray caster. Raises ``ValueError`` naming ``who`` when the view has none."""
        if self.caster is None:
            raise ValueError(f"{who} casts rays: measure(truth, scene) needs a scene with a RayCaster")
        return self.caster


@dataclass(frozen=True)
class Mount:
    """Where a sensor sits on the hull: the one mount type of every sensor, sonars included.

    Attributes:
        pos_body_m: (3,) FRD offset of the sensor from the body origin, m.
        rpy_rad: (3,) roll, pitch, yaw of the sensor frame w.r.t. the body frame, rad: ZYX Euler
            angles of the sensor -> body rotation :attr:`R_bs`, pitch positive nose *up*, as
            the vehicle's own attitude. A sonar tilted down by ``t`` has pitch ``-t`` (the
            sonars name that angle ``tilt_down_rad``; :mod:`autonomy.sonar_frame`'s
            ``(roll, tilt, yaw)`` triple is their ``mount_roll_tilt_yaw_rad``).
        site: hull site it was read from (None: given as a position).
    """

    pos_body_m: FloatArray
    rpy_rad: FloatArray = field(default_factory=lambda: np.zeros(3))
    site: str | None = None

    def __post_init__(self) -> None:
        pos = np.asarray(self.pos_body_m, dtype=float).reshape(3)
        rpy = np.asarray(self.rpy_rad, dtype=float).reshape(3)
        if not (np.all(np.isfinite(pos)) and np.all(np.isfinite(rpy))):
            raise ValueError(f"Mount: position and attitude must be finite, got {pos}, {rpy}")
        object.__setattr__(self, "pos_body_m", pos)
        object.__setattr__(self, "rpy_rad", rpy)

    @property
    def R_bs(self) -> FloatArray:
        """(3, 3) sensor frame -> body (FRD) rotation."""
        return rot_from_euler(*self.rpy_rad)

    @property
    def is_aligned(self) -> bool:
        """True when the sensor axes coincide with the body axes."""
        return not np.any(self.rpy_rad)

    @classmethod
    def from_config(cls, name: str, cfg: SensorConfig, site_pos_body: Callable[[str], ArrayLike] | None) -> "Mount":
        """The mount a config describes: ``mount_pos_body_m`` when given, else the position of
        ``mount_site`` (default: the site named ``name``) from ``site_pos_body``.

        Raises:
            ValueError: the site is needed but unknown, or no site lookup was given.
        """
        rpy = np.deg2rad(cfg.mount_rpy_deg)
        if cfg.mount_pos_body_m is not None:
            return cls(np.asarray(cfg.mount_pos_body_m, dtype=float), rpy, None)
        site = cfg.mount_site or name
        if site_pos_body is None:
            raise ValueError(f"sensors.{name}: mount_site {site!r} needs a hull (or give mount_pos_body_m)")
        try:
            pos = site_pos_body(site)
        except KeyError:
            raise ValueError(f"sensors.{name}: the hull has no site {site!r} (set mount_site or "
                             "mount_pos_body_m)") from None
        return cls(np.asarray(pos, dtype=float), rpy, site)


def as_mount(mount: Mount | ArrayLike) -> Mount:
    """A :class:`Mount`, or an aligned one at the (3,) FRD position given."""
    return mount if isinstance(mount, Mount) else Mount(np.asarray(mount, dtype=float))


class Sensor(ABC, Generic[MsgT]):
    """Base of every simulated sensor.

    Args:
        cfg: the sensor's config entry (provides ``latency_s`` and ``rate_hz``, read by
            :meth:`rate_of`).
        mount: a :class:`Mount`, or a (3,) FRD offset from the body origin (m) for a sensor
            aligned with the body.
        rng: the sensor's own generator (``sim.rng.component_rng(seed, name)``); sensors
            draw their per-run state from it in :meth:`reset`.
        name: the entry name (default: the kind).

    Attributes:
        kind: registry key, set by :func:`sim.sensors.registry.register_sensor`.
        config_type: config class of this kind.
        ground_truth_optional: class attribute, True when the sensor's messages carry ground
            truth that costs work to compute and that :attr:`render_truth` can switch off
            (the forward-looking sonar's object records and instance masks). False (the
            default): whatever truth its messages carry is always computed and
            :attr:`render_truth` has no effect.
        fixed_latency: class attribute, True (the default) when :meth:`latency_s` is the
            fixed ``cfg.latency_s`` whatever the message, so the delivery time is known at
            capture, before the message is formed (what :class:`sim.process.sonar_pipeline.SonarPipeline`
            needs to pipeline a sonar); False on a sensor whose :meth:`latency_s` depends on
            the message (the USBL's two-way travel time).
        render_truth: whether :meth:`measure` computes the optional ground truth (default
            True). Honoured by sensors with ``ground_truth_optional`` (a mission sets it False
            when none of its observers reads that truth; the message's data and the draws from
            the noise stream are the same either way); ignored by the others.
        rate_hz: sampling rate, Hz.
        mount: where it sits (the one sensor orientation: :attr:`Mount.rpy_rad`, the sensor
            frame w.r.t. the body as roll, pitch, yaw); ``mount_pos_body_m`` (3,) its FRD
            offset from the body origin, m.
        rng: the noise stream (what :meth:`reset` took).
    """

    kind: ClassVar[str] = ""
    config_type: ClassVar[type[SensorConfig]]
    ground_truth_optional: ClassVar[bool] = False
    fixed_latency: ClassVar[bool] = True
    render_truth: bool = True

    def __init__(self, cfg: SensorConfig, mount: Mount | ArrayLike, rng: np.random.Generator | None = None, *,
                 name: str | None = None) -> None:
        self.cfg = cfg
        self.name = name or cfg.kind
        self.mount = as_mount(mount)
        self.mount_pos_body_m: FloatArray = self.mount.pos_body_m
        self.rate_hz = self.rate_of(cfg)
        self._rng: np.random.Generator = rng if rng is not None else np.random.default_rng(0)
        self.reset(self._rng)

    @classmethod
    def from_config(cls, name: str, cfg: SensorConfig, mount: Mount | ArrayLike,
                    rng: np.random.Generator) -> "Sensor":
        """The sensor of entry ``name`` (what the registry calls)."""
        return cls(cfg, mount, rng, name=name)

    @classmethod
    def rate_of(cls, cfg: SensorConfig) -> float:
        """The sampling rate of a sensor of config ``cfg``, Hz (default ``cfg.rate_hz``; a sensor
        whose rate follows from its device settings overrides it)."""
        return float(cfg.rate_hz)

    @property
    def rng(self) -> np.random.Generator:
        """The sensor's noise stream (what :meth:`reset` took)."""
        return self._rng

    def latency_s(self, msg: MsgT) -> float:
        """Sampling-to-delivery delay of ``msg``, s (fixed: ``cfg.latency_s``). A sensor that
        overrides it with a delay depending on the message declares ``fixed_latency = False``."""
        return float(self.cfg.latency_s)

    def reset(self, rng: np.random.Generator) -> None:
        """Take a new noise stream and draw per-run state (biases, scale errors) from it."""
        self._rng = rng

    @abstractmethod
    def ideal(self, truth: VehicleTruth, scene: SceneView) -> Any:
        """Exact quantities at capture: the noise-free message, or what :meth:`corrupt` and
        :meth:`exact` need to form one."""

    def exact(self, ideal: Any) -> MsgT:
        """The noise-free message from :meth:`ideal`'s output (default: it is the message)."""
        return ideal

    def corrupt(self, ideal: Any, truth: VehicleTruth) -> MsgT:
        """The message with noise, biases and dropouts (default: none)."""
        return self.exact(ideal)

    def measure(self, truth: VehicleTruth, scene: SceneView | None = None, *, noise: bool = True) -> MsgT:
        """One message from the true state at ``truth.t_s`` (``noise=False``: exact values,
        no draw from the noise stream). ``scene`` may be left out by sensors that cast no
        rays and see no objects."""
        if scene is None:
            scene = SceneView(truth.t_s, None)
        ideal = self.ideal(truth, scene)
        return self.corrupt(ideal, truth) if noise else self.exact(ideal)
