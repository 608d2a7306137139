"""Side-scan sonar (SSS): the sonar parts of :mod:`sim.sensors.sonar` assembled into two lines.

Each side is one :class:`~sim.sensors.sonar.ray_fan.RayFan` (``along_track_rays`` columns
across the narrow along-track beam, ``elevation_rays`` rays from ``vertical_beamwidth_deg``
above the boresight down to the vertical) in the sonar frame of :mod:`autonomy.sonar_frame`
mounted at yaw -90 deg (port) and +90 deg (starboard), depressed by ``depression_deg``.
Surface edges are bisected (sharp shadows), small objects get finer rays
(:mod:`sim.sensors.sonar.object_rays`), each hit scatters ``cos^m`` of its incidence angle
(grazing-angle backscatter; Lambert at m = 2) weighted by the two-way vertical beam pattern,
segment energies are binned in slant range (:mod:`sim.sensors.sonar.echo_lines`), the
along-track columns are summed with the two-way along-track pattern, and both lines pass the
shared echo chain (spreading, absorption, speckle, receiver noise, TVG, display;
:mod:`sim.sensors.sonar.echo_chain`). Nothing returns before the first bottom return (the
nadir gap) and nothing from behind an object (its shadow): both come from the rays alone.
Labels come from the same echo intervals (:func:`sim.sensors.sonar.ground_truth.label_bins`).
"""

from __future__ import annotations

from collections.abc import Sequence
import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.messages import SssPing
from autonomy.sonar_frame import sonar_to_body_rotation
from scenarios.config.sss import SssConfig
from sim.sensors.base import Mount, SceneView, Sensor, as_mount
from sim.sensors.raycast import BACKGROUND_ID, RayCaster
from sim.sensors.registry import register_sensor
from sim.sensors.sonar.beam_pattern import two_way_beam_power
from sim.sensors.sonar.echo_chain import EchoChain
from sim.sensors.sonar.image_formation import formation_model
from sim.sensors.sonar.echo_lines import EchoSegments, echo_segments, ray_strength
from sim.sensors.sonar.ground_truth import SceneObjectLike, label_bins
from sim.sensors.sonar.object_rays import add_object_rays, sphere_in_window
from sim.sensors.sonar.ray_fan import RayFan, RayTable
from sim.dynamics.truth import VehicleTruth

FloatArray = NDArray[np.float64]
OBJECT_RAYS_ACROSS = 8
SIDES = ("port", "starboard")
SIDE_YAW_RAD = (-0.5 * np.pi, 0.5 * np.pi)


@dataclass(frozen=True, slots=True)
class SssRender:
    """A rendered ping and its exact labels.

    Attributes:
        ping: the message (display lines, altitude, optional ground-range lines).
        labels: (2, n_bins) int16 object id per side and slant-range bin
            (:data:`sim.sensors.raycast.BACKGROUND_ID` where no object echoes).
        ground_labels: (2, n_ground) the labels resampled to ground range (None without).
        mean_intensity: (2, n_bins) noise-free received power before TVG (linear).
        intensity: (2, n_bins) the realisation with speckle and noise.
        pos_ned: (3,) transducer position at the ping, NED m; R_nb: (3, 3) body -> NED.
    """

    ping: SssPing
    labels: NDArray[np.int16]
    ground_labels: NDArray[np.int16] | None
    mean_intensity: NDArray[np.float32]
    intensity: NDArray[np.float32]
    pos_ned: FloatArray
    R_nb: FloatArray

    @property
    def t_s(self) -> float:
        """Ping time, s."""
        return self.ping.t_s


def ground_range_resample(lines: NDArray, altitude_m: float, bin_size_m: float, *, nearest: bool = False
                          ) -> NDArray:
    """Slant-range lines (2, n_bins) -> ground-range lines (2, n_bins) on a flat seabed.

    Ground bin j (centre ``g = (j + 0.5) bin_size_m`` from nadir) takes the slant range
    ``sqrt(g^2 + h^2)`` (``h = altitude_m``), linearly interpolated between slant-bin
    centres (``nearest``: the slant bin holding it, for labels); beyond the last slant bin it
    is 0 (:data:`BACKGROUND_ID` for labels).

    Raises:
        ValueError: ``altitude_m`` is not finite and non-negative.
    """
    if not (np.isfinite(altitude_m) and altitude_m >= 0.0):
        raise ValueError(f"ground-range correction needs a finite altitude >= 0, got {altitude_m}")
    n_bins = lines.shape[-1]
    g = (np.arange(n_bins) + 0.5) * bin_size_m
    u = np.sqrt(g * g + altitude_m * altitude_m) / bin_size_m  # slant range in bin units
    if nearest:
        k = np.floor(u).astype(np.intp)
        out = np.full_like(lines, BACKGROUND_ID)
        ok = k < n_bins
        out[:, ok] = lines[:, k[ok]]
        return out
    centres = np.arange(n_bins) + 0.5
    out = np.stack([np.interp(u, centres, row, right=0.0) for row in lines.astype(np.float64)])
    return out.astype(lines.dtype)


@dataclass(frozen=True, slots=True)
class SssEcho:
    """The noise-free part of a ping (:meth:`SssSensor.ideal`): everything up to the first draw
    from the noise stream.

    Attributes:
        t_s: ping time, s.
        mean_intensity: (2, n_bins) float32 expected received power before TVG (linear).
        labels: (2, n_bins) int16 object id per side and slant-range bin.
        altitude_m: the shorter range of the two vertical rays, m (nan if none).
        pos_ned: (3,) transducer position, NED m; R_nb: (3, 3) body -> NED.
    """

    t_s: float
    mean_intensity: NDArray[np.float32]
    labels: NDArray[np.int16]
    altitude_m: float
    pos_ned: FloatArray
    R_nb: FloatArray


@register_sensor(SssConfig)
class SssSensor(Sensor[SssRender]):
    """Port and starboard side-scan lines per ping, with per-bin object labels.

    Args:
        cfg: the side-scan config.
        mount: both transducers' position on the hull (its attitude must be zero; the sides
            are at yaw -+90 deg and depressed by ``cfg.depression_deg``).
        rng: speckle and receiver-noise stream (``sim.rng.component_rng(seed, name)``).
        name: entry name (default ``sss``).

    Attributes:
        rate_hz: ping rate, Hz (``cfg.rate_hz``, by default the two-way travel-time limit).
        bin_size_m: slant-range bin size, m.
        side_R_bs: per side (port, starboard) the (3, 3) transducer (sonar frame) -> body rotation.
    """

    def __init__(self, cfg: SssConfig, mount: Mount | ArrayLike = (0.0, 0.0, 0.0),
                 rng: np.random.Generator | None = None, *, name: str | None = None) -> None:
        super().__init__(cfg, mount, rng, name=name)
        self.cfg: SssConfig = cfg
        self.n_bins = int(cfg.n_bins)
        self.bin_size_m = float(cfg.range_max_m) / self.n_bins
        dep = np.deg2rad(cfg.depression_deg)
        vbw = np.deg2rad(cfg.vertical_beamwidth_deg)
        self.vertical_beamwidth_rad = float(vbw)
        # elevations in the sonar frame (down > 0): from vbw above the boresight to the vertical
        el = np.linspace(-vbw, 0.5 * np.pi - dep, cfg.elevation_rays)
        atbw = np.deg2rad(cfg.along_track_beamwidth_deg)
        n_at = cfg.along_track_rays
        az = np.zeros(1) if n_at == 1 else np.linspace(-atbw, atbw, n_at)
        w = two_way_beam_power(az, atbw)
        self.column_weight = w / w.sum()
        self.fan = RayFan(az, el)
        self.side_R_bs = [sonar_to_body_rotation((0.0, dep, yaw)) for yaw in SIDE_YAW_RAD]
        bins = (np.arange(self.n_bins) + 0.5) * self.bin_size_m
        self.echo = EchoChain(bins, cfg.absorption_db_per_m, cfg.tvg_spreading_db_per_decade,
                              cfg.absorption_db_per_m if cfg.tvg_absorption else 0.0, cfg.noise_floor_db,
                              cfg.speckle, cfg.k_shape, cfg.gain_db, cfg.dynamic_range_db,
                              formation=formation_model(cfg.formation, bins, self.bin_size_m, np.pi, atbw,
                                                        cfg.absorption_db_per_m, 0.0))

    @classmethod
    def from_config(cls, name: str, cfg: SssConfig, mount: Mount | ArrayLike,
                    rng: np.random.Generator) -> "SssSensor":
        m = as_mount(mount)
        if not m.is_aligned:
            raise ValueError(f"sensors.{name}: a side-scan mount has no attitude (use depression_deg)")
        return cls(cfg, m, rng, name=name)

    # -- sensor contract --------------------------------------------------------------------
    def ideal(self, truth: VehicleTruth, scene: SceneView) -> SssEcho:
        """The noise-free ping from the true vehicle state among the scene's objects at
        capture time: expected power, labels and altitude.

        Raises:
            ValueError: the scene has no ray caster.
        """
        return self.echo_at(truth.t_s, truth.point_ned(self.mount_pos_body_m), truth.R_nb,
                            scene.require_caster("SssSensor"), scene.objects)

    def exact(self, ideal: SssEcho) -> SssRender:
        """The expected ping: mean power plus the noise floor, nothing drawn."""
        return self._ping(ideal, noise=False)

    def corrupt(self, ideal: SssEcho, truth: VehicleTruth) -> SssRender:
        """The ping with speckle and receiver noise drawn from the sensor's stream."""
        return self._ping(ideal, noise=True)

    # -- rendering --------------------------------------------------------------------------
    def echo_intervals(self, origin_ned: FloatArray, R_nb: FloatArray, caster: RayCaster,
                      objects: Sequence[SceneObjectLike],
                      spheres: dict[int, tuple[FloatArray, float]] | None = None) -> tuple[EchoSegments, float]:
        """Echo intervals of both sides (line 0 port, 1 starboard), along-track columns summed
        with their beam-pattern weights; and the shorter range of the two vertical rays (m, inf
        if none).

        Each side casts its base rays and the finer rays over its objects; the edge bisection
        and the echo intervals then run on both sides' rays at once (starboard columns offset by
        ``n_cols``; one cast per bisection level for both).

        ``spheres``: object id -> bounding sphere (centre (3,) NED m, radius m), shared by both
        sides of a ping (default: asked of the caster)."""
        cfg, fan = self.cfg, self.fan
        R_ns = np.stack([R_nb @ R_bs for R_bs in self.side_R_bs])
        rmax = float(cfg.range_max_m)
        tables, pairs_a, pairs_b, vertical = [], [], [], float("inf")
        n_rows = 0
        for side in (0, 1):
            base, _ = fan.cast(caster, origin_ned, R_ns[side], rmax)
            sampled, _, pairs = add_object_rays(fan, base, caster, origin_ned, R_ns[side], objects, 0.0, rmax, rmax,
                                                OBJECT_RAYS_ACROSS, spheres=spheres)
            pa, pb = fan.base_pairs if pairs is None else pairs
            if side:
                sampled = dataclasses.replace(sampled, col=sampled.col + fan.n_cols)
            tables.append(sampled)
            pairs_a.append(pa + n_rows)
            pairs_b.append(pb + n_rows)
            n_rows += len(sampled.dist)
            centre = fan.n_cols // 2
            vertical = min(vertical, float(base.dist[centre * fan.n_el + fan.n_el - 1]))
        rays, segs = fan.refine_edges(caster, origin_ned, R_ns, RayTable.stack(tables), rmax, rmax,
                                      cfg.edge_refine_iters, (np.concatenate(pairs_a), np.concatenate(pairs_b)))
        strength = ray_strength(rays, cfg.scattering_exponent, self.vertical_beamwidth_rad, fan.elevation_step_rad)
        side_of = rays.col // fan.n_cols
        slope = np.empty(len(rays.dist))
        for side in (0, 1):
            rows = np.flatnonzero(side_of == side)
            slope[rows] = fan.range_slope(rays.take(rows), R_ns[side])
        e = echo_segments(rays, segs, strength, slope, 0.0, self.bin_size_m)
        return EchoSegments(e.line // fan.n_cols, e.u0, e.u1, e.energy * self.column_weight[e.line % fan.n_cols],
                            e.obj), vertical

    def render(self, t_s: float, pos_ned: ArrayLike, R_nb: ArrayLike, caster: RayCaster,
               objects: Sequence[SceneObjectLike] = (), *, noise: bool = True) -> SssRender:
        """Render one ping (:meth:`echo_at`, then the noise, the display and the ground-range lines).

        Args:
            t_s: ping time, s.
            pos_ned: (3,) transducer position, NED m.
            R_nb: (3, 3) body (FRD) -> NED rotation.
            caster: the scene (MuJoCo or analytic).
            objects: scene objects to label (finer rays over each).
            noise: draw speckle and receiver noise (False: mean power plus the noise floor).
        """
        return self._ping(self.echo_at(t_s, pos_ned, R_nb, caster, objects), noise=noise)

    def echo_at(self, t_s: float, pos_ned: ArrayLike, R_nb: ArrayLike, caster: RayCaster,
                objects: Sequence[SceneObjectLike] = ()) -> SssEcho:
        """The noise-free part of :meth:`render` (same arguments): expected power, labels and
        altitude. Draws nothing."""
        origin = np.asarray(pos_ned, dtype=float).reshape(3)
        R = np.asarray(R_nb, dtype=float).reshape(3, 3)
        spheres = None
        if objects and hasattr(caster, "object_bounding_sphere"):  # once per ping, not per side
            spheres = {int(o.id): caster.object_bounding_sphere(int(o.id)) for o in objects}
            # both sides share the range window: drop the objects out of range once
            rmax = float(self.cfg.range_max_m)
            objects = [o for o in objects
                       if sphere_in_window(np.asarray(spheres[int(o.id)][0], dtype=float) - origin,
                                           spheres[int(o.id)][1], 0.0, rmax)]
        seg, altitude = self.echo_intervals(origin, R, caster, objects, spheres)
        altitude = altitude if np.isfinite(altitude) else float("nan")
        mean = self.echo.mean_intensity(seg.lines(2, self.n_bins, dtype=np.float32))
        labels, _ = label_bins(seg, 2, self.n_bins)
        return SssEcho(t_s=float(t_s), mean_intensity=mean, labels=labels, altitude_m=altitude, pos_ned=origin, R_nb=R)

    def _ping(self, echo: SssEcho, *, noise: bool) -> SssRender:
        """The ping of ``echo``: speckle and receiver noise (``noise``: drawn from the sensor's
        stream; else the expected intensity), the dB display and, with ``cfg.ground_range``,
        the ground-range lines."""
        mean, labels, altitude = echo.mean_intensity, echo.labels, echo.altitude_m
        intensity = self.echo.realise(mean, self._rng, noise=noise, clutter=labels < 0)
        lines_u8 = self.echo.display(intensity)
        ground_u8 = ground_labels = None
        if self.cfg.ground_range and np.isfinite(altitude):
            ground_u8 = ground_range_resample(lines_u8, altitude, self.bin_size_m)
            ground_labels = ground_range_resample(labels, altitude, self.bin_size_m, nearest=True)
        ping = SssPing(t_s=echo.t_s, lines_u8=lines_u8, bin_size_m=self.bin_size_m, altitude_m=altitude,
                       ground_lines_u8=ground_u8, mount_pos_body_m=self.mount_pos_body_m.copy())
        return SssRender(ping=ping, labels=labels, ground_labels=ground_labels, mean_intensity=mean,
                         intensity=intensity, pos_ned=echo.pos_ned.copy(), R_nb=echo.R_nb.copy())


class Waterfall:
    """Accumulates pings into a waterfall image: one row per ping, port on the left (far range
    at column 0), starboard on the right.

    Args:
        n_bins: bins per side.
    """

    def __init__(self, n_bins: int) -> None:
        self.n_bins = int(n_bins)
        self._rows: list[NDArray[np.uint8]] = []
        self._labels: list[NDArray[np.int16]] = []

    def add(self, render: SssRender) -> None:
        """Append a ping's lines and labels."""
        lines = render.ping.lines_u8
        self._rows.append(np.concatenate([lines[0, ::-1], lines[1]]))
        self._labels.append(np.concatenate([render.labels[0, ::-1], render.labels[1]]))

    def image(self) -> NDArray[np.uint8]:
        """(n_pings, 2 n_bins) uint8."""
        return np.stack(self._rows) if self._rows else np.zeros((0, 2 * self.n_bins), np.uint8)

    def labels(self) -> NDArray[np.int16]:
        """(n_pings, 2 n_bins) object ids."""
        return np.stack(self._labels) if self._labels else np.zeros((0, 2 * self.n_bins), np.int16)
