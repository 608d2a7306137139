"""Forward-looking sonar (FLS): the sonar parts of :mod:`sim.sensors.sonar` assembled into a fan.

Rays: ``azimuth_columns`` x ``elevation_rays`` directions, fixed in the sonar frame of
:mod:`autonomy.sonar_frame`, rotated into NED with one matmul per frame; surface edges are
located by bisection (``edge_refine_iters`` extra casts of one ray per edge)
(:mod:`sim.sensors.sonar.ray_fan`). Objects the base rays sample coarsely (a small sphere
between two elevation rays) are sampled by finer sub-columns over their bounding spheres, so
each echoes, is labelled and has its nearest range resolved. Each column becomes an echo line
(:mod:`sim.sensors.sonar.echo_lines`), the lines pass the echo chain (spreading, absorption,
azimuth beam pattern, speckle, noise, TVG, gain; :mod:`sim.sensors.sonar.echo_chain`) and are
resampled into the fan image. Ground truth comes from the same rays
(:mod:`sim.sensors.sonar.ground_truth`): a polar/fan instance mask and, per object, its box,
visible fraction and the true polar position of its centroid. A render without them
(``truth=False``, or :attr:`FlsSensor.render_truth` False: a mission none of whose observers
reads them) skips the objects' truth (its extra isolated ray casts) and, unless the K-distributed
texture reads the clutter mask, the mask; the image and the noise stream are the same bytes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.guidance.lawnmower import fls_swath_width_m
from autonomy.messages import FlsFrame
from autonomy.sonar_geometry import FanGeometry
from scenarios.config.fls import FlsConfig
from sim.sensors.base import Mount, SceneView, Sensor, as_mount
from scenarios.fls_presets import FlsGeometry, resolve_geometry
from sim.sensors.raycast import RayCaster
from sim.sensors.sonar.beam_pattern import azimuth_kernel
from sim.sensors.sonar.display import FanRemap
from sim.sensors.sonar.echo_chain import EchoChain
from sim.sensors.sonar.echo_lines import EchoSegments, echo_segments, ray_strength, spread_segments
from sim.sensors.sonar.image_formation import formation_model, object_tail, specular_objects
from sim.sensors.sonar.ground_truth import (
    SceneObjectLike,
    SonarGroundTruth,
    SonarObjectTruth,
    centroid_polar,
    label_bins,
    visible_fraction,
)
from sim.sensors.registry import register_sensor
from sim.sensors.sonar.object_rays import add_object_rays
from sim.sensors.sonar.ray_fan import RayFan, RayTable, Segments
from sim.dynamics.truth import VehicleTruth

FloatArray = NDArray[np.float64]
OBJECT_RAYS_ACROSS = 8  # rays across an object (each way) where the base rays are sparser
SHELL_MAX_RADIUS_M = 1.0  # objects larger than this (walls, structures) are solid: no back-wall echo
BACK_WALL_MAX_M = 2.0  # far walls deeper than this behind the near wall are not echoed
OBJECT_RAYS_SPAN_LIMIT = 3.0  # objects spanning this many base ray spacings or more keep the base rays


@dataclass(frozen=True, slots=True)
class FlsRender:
    """A rendered frame, its ground truth, and the linear intensities behind the image.

    ``mean_intensity``: (n_beams, n_bins) noise-free expected power before TVG;
    ``intensity``: the realisation with speckle and noise (equal to mean + noise floor
    when rendered with ``noise=False``).
    """

    frame: FlsFrame
    truth: SonarGroundTruth
    mean_intensity: NDArray[np.float32]
    intensity: NDArray[np.float32]


@dataclass(frozen=True, slots=True)
class FlsEcho:
    """The noise-free part of a frame (:meth:`FlsSensor.ideal`): everything up to the first
    draw from the noise stream.

    Attributes:
        t_s: capture time, s.
        mean_intensity: (n_beams, n_bins) float32 expected power before TVG.
        truth: the frame's ground truth (objects and mask only when rendered with them).
        clutter: (n_beams, n_bins) bins the K texture applies to (None unless ``speckle == "k"``).
    """

    t_s: float
    mean_intensity: NDArray[np.float32]
    truth: SonarGroundTruth
    clutter: NDArray[np.bool_] | None


@register_sensor(FlsConfig)
class FlsSensor(Sensor[FlsRender]):
    """Forward-looking sonar on the hull.

    Args:
        cfg: the sonar config (preset + overrides).
        mount: a :class:`Mount` (position, roll and yaw used; the tilt is ``cfg.tilt_deg``) or a
            (3,) FRD offset of the sonar head from the body origin, m.
        rng: generator for speckle and noise (``sim.rng.component_rng(seed, name)``).
        name: the sensor's entry name (default ``fls``).

    Attributes:
        mount: the head's mount; its ``rpy_rad`` is ``(roll, -tilt_down_rad, yaw)`` (pitch up > 0,
            as every :class:`Mount`) and ``R_bs`` (also :attr:`R_bs`) the sonar -> body rotation.
        tilt_down_rad: depression of the boresight below the body's x-y plane, rad (``cfg.tilt_deg``).
        render_truth: whether :meth:`render` (and so :meth:`measure`) computes the objects'
            ground truth and the instance mask when not told (default True;
            :class:`sim.mission.Mission` sets it from its observers' ``sonar_truth``). The
            class declares ``ground_truth_optional``.
    """

    ground_truth_optional = True
    render_truth: bool = True

    def __init__(self, cfg: FlsConfig, mount: Mount | ArrayLike = (0.0, 0.0, 0.0),
                 rng: np.random.Generator | None = None, *, name: str | None = None) -> None:
        m = as_mount(mount)
        self.tilt_down_rad = float(np.deg2rad(cfg.tilt_deg))
        super().__init__(cfg, Mount(m.pos_body_m, np.array([m.rpy_rad[0], -self.tilt_down_rad, m.rpy_rad[2]]),
                                    m.site), rng, name=name)
        self.cfg: FlsConfig = cfg
        self.R_bs = self.mount.R_bs
        self.geometry: FlsGeometry = resolve_geometry(cfg)
        g = self.geometry

        self.n_bins = g.n_bins
        self.rays = RayFan(g.column_azimuths_rad(), g.elevations_rad())
        n_cols = self.rays.n_cols
        self._ray_spacing_rad = max(self.rays.elevation_step_rad, g.fov_rad / n_cols)
        self.echo = EchoChain(
            g.bin_centres_m(), g.absorption_db_per_m, cfg.tvg_spreading_db_per_decade,
            g.absorption_db_per_m if cfg.tvg_absorption else 0.0, cfg.noise_floor_db, cfg.speckle, cfg.k_shape,
            cfg.gain_db, cfg.dynamic_range_db,
            azimuth_kernel(g.fov_rad / n_cols, g.beamwidth_az_rad, cfg.side_lobe_extent_beamwidths,
                           cfg.formation.side_lobe_floor_db),
            formation=formation_model(cfg.formation, g.bin_centres_m(), g.range_resolution_m, g.beam_spacing_rad,
                                      g.beamwidth_az_rad, g.absorption_db_per_m, cfg.side_lobe_extent_beamwidths),
            counter_speckle=cfg.speckle_generator == "counter")
        beam_az = g.beam_azimuths_rad()
        col_az = self.rays.column_azimuths_rad
        col_step = g.fov_rad / n_cols
        self._beam_col = np.clip(np.round((beam_az - col_az[0]) / col_step), 0, n_cols - 1).astype(np.intp)
        self._bbox_beam_pad = int(np.ceil(0.5 * g.beamwidth_az_rad / g.beam_spacing_rad))
        w, h = g.fan_size_px
        self.fan_geometry = FanGeometry.fit(w, h, g.window_near_m, g.window_far_m, g.fov_rad)
        self._remap = FanRemap(self.fan_geometry, beam_az, g.window_near_m, g.range_resolution_m, self.n_bins)

    # -- sensor contract --------------------------------------------------------------------
    def ideal(self, truth: VehicleTruth, scene: SceneView) -> FlsEcho:
        """The noise-free frame from the true vehicle state (sonar head at the mount point)
        among the scene's objects at capture time: expected intensities and ground truth.

        Raises:
            ValueError: the scene has no ray caster.
        """
        return self.echo_at(truth.t_s, truth.point_ned(self.mount_pos_body_m), truth.R_nb,
                            scene.require_caster("FlsSensor"), scene.objects)

    def exact(self, ideal: FlsEcho) -> FlsRender:
        """The expected frame: intensity = mean + noise floor, nothing drawn."""
        return self._frame(ideal, noise=False)

    def corrupt(self, ideal: FlsEcho, truth: VehicleTruth) -> FlsRender:
        """The frame with speckle and receiver noise drawn from the sensor's stream."""
        return self._frame(ideal, noise=True)

    # -- public ---------------------------------------------------------------------------
    @property
    def mount_roll_tilt_yaw_rad(self) -> FloatArray:
        """(3,) the mount as ``(roll, tilt down > 0, yaw)``, rad: the convention of
        :mod:`autonomy.sonar_frame` (what the frames carry as ``FlsFrame.mount_rpy_rad`` and
        the on-board geolocalisation takes)."""
        return np.array([self.mount.rpy_rad[0], self.tilt_down_rad, self.mount.rpy_rad[2]])

    @property
    def n_rays(self) -> int:
        """Base rays per frame (edge refinement adds a few per discontinuity)."""
        return self.rays.n_rays

    def swath_width_m(self, altitude_m: float) -> float:
        """Across-track width of flat seabed seen at ``altitude_m`` (level vehicle)."""
        g = self.geometry
        return fls_swath_width_m(altitude_m, self.tilt_down_rad, g.fov_rad, g.vertical_beamwidth_rad,
                                 g.window_near_m, g.window_far_m)

    def render(self, t_s: float, pos_ned: ArrayLike, R_nb: ArrayLike, caster: RayCaster,
               objects: Sequence[SceneObjectLike] = (), *, noise: bool = True,
               truth: bool | None = None) -> FlsRender:
        """Render one frame (:meth:`echo_at`, then the noise, the display and the fan image).

        Args:
            t_s: capture time.
            pos_ned: (3,) NED position of the sonar head.
            R_nb: (3, 3) body->NED rotation of the vehicle.
            caster: the scene (MuJoCo or analytic).
            objects: scene objects to report ground truth for (their echoes are sampled
                finely either way).
            noise: draw speckle and receiver noise (False: expected image).
            truth: compute the objects' ground truth and the instance mask (None:
                :attr:`render_truth`). False: the returned truth holds the sonar pose only
                (reading its objects or masks raises
                :class:`sim.sensors.sonar.ground_truth.SonarTruthNotComputedError`); the
                frame, the intensities and the draws from the noise generator are the same.
        """
        return self._frame(self.echo_at(t_s, pos_ned, R_nb, caster, objects, truth=truth), noise=noise)

    def echo_at(self, t_s: float, pos_ned: ArrayLike, R_nb: ArrayLike, caster: RayCaster,
                objects: Sequence[SceneObjectLike] = (), *, truth: bool | None = None) -> FlsEcho:
        """The noise-free part of :meth:`render` (same arguments): the rays, the expected
        intensities and the ground truth. Draws nothing."""
        if truth is None:
            truth = self.render_truth
        g, cfg = self.geometry, self.cfg
        origin = np.asarray(pos_ned, dtype=float).reshape(3)
        R_ns = np.asarray(R_nb, dtype=float) @ self.R_bs
        base_rays, _ = self.rays.cast(caster, origin, R_ns, g.range_max_m)
        spheres = ({int(o.id): caster.object_bounding_sphere(int(o.id)) for o in objects}
                   if objects and hasattr(caster, "object_bounding_sphere") else None)
        sampled, owner, pairs = self._add_object_rays(base_rays, caster, origin, R_ns, objects, spheres)
        rays, segments = self.rays.refine_edges(caster, origin, R_ns, sampled, g.range_max_m, g.window_far_m,
                                                cfg.edge_refine_iters, pairs)
        strength = ray_strength(rays, cfg.scattering_exponent, g.vertical_beamwidth_rad,
                                self.rays.elevation_step_rad)
        form = self.echo.formation
        if form is not None and form.specular_share > 0.0:
            strength = specular_objects(strength, rays, cfg.scattering_exponent, form.specular_share,
                                        form.specular_exponent)
        slope = self.rays.range_slope(rays, R_ns)
        echoes = echo_segments(rays, segments, strength, slope, g.window_near_m, g.range_resolution_m)
        if form is not None and form.back_wall_ratio > 0.0:
            echoes = self._with_back_walls(echoes, rays, segments, strength, slope, origin, caster)
        n_cols = self.rays.n_cols
        lines = echoes.lines(n_cols, self.n_bins, dtype=np.float32)
        if form is not None and form.has_tail and np.any(echoes.obj >= 0):
            on = echoes.obj >= 0
            obj_lines = spread_segments(n_cols, self.n_bins, echoes.line[on], echoes.u0[on], echoes.u1[on],
                                        echoes.energy[on], dtype=np.float32)
            lines += object_tail(obj_lines, form.tail_decay, form.tail_ratio)
        mean = self.echo.mean_intensity(lines)
        mask = extents = None
        if truth or self.echo.needs_clutter:  # the K and seabed textures read the clutter mask
            mask, extents = label_bins(echoes, n_cols, self.n_bins)
        if n_cols != g.n_beams:
            mean = cv2.resize(mean, (self.n_bins, g.n_beams), interpolation=cv2.INTER_LINEAR)
            if mask is not None:
                mask = mask[self._beam_col]
        clutter = (mask < 0) if self.echo.needs_clutter else None  # only the textures read it
        objs = self._objects_truth(objects, origin, R_ns, sampled, owner, extents, caster, spheres) if truth else None
        record = SonarGroundTruth(t_s=float(t_s), mask_polar=mask if truth else None, objects=objs,
                                  pos_ned=origin.copy(), R_ns=R_ns, fan_remap=self._remap)
        return FlsEcho(t_s=float(t_s), mean_intensity=mean, truth=record, clutter=clutter)

    def _with_back_walls(self, echoes: EchoSegments, rays: RayTable, segments: Segments, strength: FloatArray,
                         slope: FloatArray, origin: FloatArray, caster: RayCaster) -> EchoSegments:
        """``echoes`` and the back-wall echoes of the object hits
        (:mod:`sim.sensors.sonar.image_formation`): each ray on an object is followed through
        it to where it leaves it (``caster.exit_distances``); the ``k``-th echo comes
        ``k`` wall-to-wall crossings after the near wall's with ``back_wall_ratio ** k`` of its
        strength. Intervals join rays that leave the same object only. Objects whose bounding
        sphere is larger than :data:`SHELL_MAX_RADIUS_M` (a tank wall, a structure) are solid
        and get none.

        Raises:
            ValueError: the caster cannot cast from points (the analytic test caster).
        """
        form = self.echo.formation
        exits = getattr(caster, "exit_distances", None)
        if exits is None:
            raise ValueError("formation.object_back_wall_ratio needs a caster that finds where rays leave objects "
                             f"(MujocoRayCaster); {type(caster).__name__} does not")
        hit = np.flatnonzero((rays.obj >= 0) & np.isfinite(rays.dist))
        if hit.size:
            ids = np.unique(rays.obj[hit])
            solid = [k for k in ids if caster.object_bounding_sphere(int(k))[1] > SHELL_MAX_RADIUS_M]
            hit = hit[~np.isin(rays.obj[hit], solid)]
        if hit.size == 0:
            return echoes
        pts = origin[None, :] + rays.dirs[hit] * rays.dist[hit][:, None]
        d = exits(pts, rays.dirs[hit], rays.obj[hit])
        ok = np.isfinite(d) & (d > 1e-6) & (d <= BACK_WALL_MAX_M)
        if not np.any(ok):
            return echoes
        hit, cross = hit[ok], d[ok]
        inside = np.zeros(len(rays.dist), dtype=bool)
        inside[hit] = True
        a, b = segments.a, segments.b
        seg = Segments(a, b, segments.connected & inside[a] & inside[b] & (rays.obj[a] == rays.obj[b]))
        parts = [echoes]
        g = self.geometry
        for k in range(1, form.back_wall_repeats + 1):
            dist = rays.dist.copy()
            dist[hit] += k * cross
            s = np.zeros_like(strength)
            s[hit] = strength[hit] * form.back_wall_ratio ** k
            parts.append(echo_segments(replace(rays, dist=dist), seg, s, slope, g.window_near_m,
                                       g.range_resolution_m))
        return EchoSegments(*(np.concatenate([getattr(p, f) for p in parts])
                              for f in ("line", "u0", "u1", "energy", "obj")))

    def _frame(self, echo: FlsEcho, *, noise: bool) -> FlsRender:
        """The frame of ``echo``: speckle and receiver noise (``noise``: drawn from the sensor's
        stream; else the expected intensity), the dB display and the fan image."""
        intensity, polar_u8 = self.echo.realise_display(echo.mean_intensity, self._rng, noise=noise,
                                                        clutter=echo.clutter)
        fan_u8 = self._remap.image(polar_u8)
        frame = FlsFrame(t_s=echo.t_s, polar=polar_u8, fan=fan_u8, geometry=self.fan_geometry,
                         mount_pos_body_m=self.mount_pos_body_m.copy(), mount_rpy_rad=self.mount_roll_tilt_yaw_rad)
        return FlsRender(frame=frame, truth=echo.truth, mean_intensity=echo.mean_intensity, intensity=intensity)

    # -- internals --------------------------------------------------------------------------
    def _add_object_rays(self, base: RayTable, caster: RayCaster, origin: FloatArray, R_ns: FloatArray,
                         objects: Sequence[SceneObjectLike], spheres: dict[int, tuple[FloatArray, float]] | None = None
                         ) -> tuple[RayTable, NDArray[np.int64], tuple[NDArray[np.intp], NDArray[np.intp]] | None]:
        """Finer rays over objects the base rays sample coarsely
        (:func:`sim.sensors.sonar.object_rays.add_object_rays` over the range window)."""
        g = self.geometry
        return add_object_rays(self.rays, base, caster, origin, R_ns, objects, g.window_near_m, g.window_far_m,
                               g.range_max_m, OBJECT_RAYS_ACROSS, OBJECT_RAYS_SPAN_LIMIT, spheres=spheres)

    def _objects_truth(self, objects: Sequence[SceneObjectLike], origin: FloatArray, R_ns: FloatArray,
                       sampled: RayTable, owner: NDArray[np.int64], extents: dict[int, tuple[int, int, int, int]],
                       caster: RayCaster, spheres: dict[int, tuple[FloatArray, float]] | None
                       ) -> tuple[SonarObjectTruth, ...]:
        """Truth records of ``objects`` from the sampled rays (``owner``: the object whose sphere
        each samples, -1 for base rays, -2 for sub-column rays at base elevations; ``extents``:
        :func:`label_bins`'s; ``spheres``: the caster's bounding spheres, if it has them). An
        object is counted on the base rays and on the rays of its own sphere only: two even
        samplings of its cone, whatever other objects were refined."""
        if not objects:
            return ()
        g = self.geometry
        in_win = (sampled.dist >= g.window_near_m) & (sampled.dist <= g.window_far_m)
        first_obj = sampled.obj
        # rays that count for the object they hit first: in the window, a base ray or one of its sphere
        counted = in_win & (first_obj >= 0) & ((owner < 0) | (owner == first_obj))
        hits_per_id = np.bincount(first_obj[counted])
        base_only = not np.any(owner >= 0)
        out = []
        for obj in objects:
            k = int(obj.id)
            n_hit = int(hits_per_id[k]) if 0 <= k < len(hits_per_id) else 0
            rows = None if base_only else (owner < 0) | (owner == k)
            frac = visible_fraction(caster, k, origin, sampled.dirs, first_obj, n_hit, g.window_near_m,
                                    g.window_far_m, g.range_max_m, self._ray_spacing_rad, rows=rows,
                                    sphere=None if spheres is None else spheres[k])
            out.append(self._object_truth(obj, origin, R_ns, n_hit, frac, extents.get(k)))
        return tuple(out)

    def _object_truth(self, obj: SceneObjectLike, origin: FloatArray, R_ns: FloatArray, n_hit: int, frac: float,
                      extent: tuple[int, int, int, int] | None) -> SonarObjectTruth:
        """Truth record of ``obj`` given its first-hit ray count and visible fraction."""
        g = self.geometry
        k = int(obj.id)
        pos = np.asarray(obj.centroid_ned, dtype=float)
        rng_m, az, el = centroid_polar(pos, origin, R_ns)
        in_fov = bool(abs(az) <= 0.5 * g.fov_rad and abs(el) <= 0.5 * g.vertical_beamwidth_rad
                      and g.window_near_m <= rng_m <= g.window_far_m)
        bbox = bbox_polar = None
        if extent is not None:
            c0, c1, k0, k1 = extent
            pb, nb = self._bbox_beam_pad, self.n_bins
            beam0 = int(np.searchsorted(self._beam_col, c0, side="left"))
            beam1 = int(np.searchsorted(self._beam_col, c1, side="right")) - 1
            b0, b1 = max(beam0 - pb, 0), min(beam1 + pb, g.n_beams - 1)
            k0, k1 = max(k0 - 1, 0), min(k1 + 1, nb - 1)
            bbox_polar = (b0, k0, b1, k1)
            bbox = self._remap.box_px(b0, k0, b1, k1)
        visible = n_hit > 0 and bbox is not None and (
            np.isnan(frac) or frac >= self.cfg.min_visible_fraction)
        return SonarObjectTruth(
            id=k, name=str(obj.name), class_name=str(obj.class_name), is_target=bool(obj.is_target),
            visible=bool(visible), visible_fraction=frac, n_rays_hit=n_hit, in_fov=in_fov, bbox_xyxy=bbox,
            bbox_polar=bbox_polar, range_m=rng_m, azimuth_rad=az, elevation_rad=el, pos_ned=pos.copy())
