"""FLS rendering benchmark: frames per second on one core for a survey pose of a scenario.

``auvsim bench fls`` renders the scenario's scene (the ``cssn_lawnmower`` basin by default)
from a survey pose, 2 m above the seabed looking along the target rows, with the
scenario's sonar limited to a 30 m range window, noise on, ground truth included; then the
same frames again without the ground truth (what the mission renders when no observer reads
it: no scoring, no recording), from the same noise state; the first frames are rendered again
both ways, untimed, and compared byte for byte. With ``baseline`` (the default when the
scenario uses the counter-based speckle), the same frames are rendered again in the same run by
the renderer before the speed-ups of the RL-throughput work (``speckle_generator: stream``:
every pixel drawn from the generator's stream, the display in its own passes; MuJoCo's ray
casts), by the scenario's renderer, and, where ``embreex`` is installed, by the scenario's
renderer with Embree's ray casts (``physics.ray_caster: embree``), interleaved in rounds so that
a machine's drift falls on all; each one's ``speedup_cpu`` is its frames per CPU-second over the
renderer before's.
"""

from __future__ import annotations

import time

import numpy as np

from autonomy.frames import rot_from_euler
from scenarios.config.fls import FlsConfig
from scenarios.load import ScenarioError
from scenarios.schema import Scenario
from sim.rng import component_rng
from sim.sensors.fls import FlsSensor
from sim.sensors.embree_scene import available as embree_available
from sim.sensors.raycast import MujocoRayCaster
from sim.scene.world import build_world
from scenarios.fls_presets import PRESETS

IDENTITY_FRAMES = 10  # frames rendered again, untimed, with and without the truth to compare


class _TimedCaster:
    """Forwards to a caster, timing its ray casts and counting rays."""

    def __init__(self, caster: MujocoRayCaster) -> None:
        self.caster = caster
        self.time_s = 0.0
        self.n_rays = 0

    def cast(self, origin_ned, dirs_ned, max_range_m):
        t0 = time.perf_counter()
        hits = self.caster.cast(origin_ned, dirs_ned, max_range_m)
        self.time_s += time.perf_counter() - t0
        self.n_rays += len(dirs_ned)
        return hits

    def cast_isolated(self, origin_ned, dirs_ned, max_range_m, object_id):
        t0 = time.perf_counter()
        dist = self.caster.cast_isolated(origin_ned, dirs_ned, max_range_m, object_id)
        self.time_s += time.perf_counter() - t0
        self.n_rays += len(dirs_ned)
        return dist

    def object_bounding_sphere(self, object_id):
        return self.caster.object_bounding_sphere(object_id)


def check_scenario(scenario: Scenario) -> None:
    """Raise ``ScenarioError`` (one line) when ``scenario`` has no FLS entry ``sensors.fls`` to render."""
    base = scenario.sensors.get("fls")
    if base is None or base.kind != "fls":
        raise ScenarioError(f"--scenario {scenario.name}: has no forward-looking sonar entry sensors.fls (kind fls) "
                            "for bench fls to render; use cssn_lawnmower or a scenario with one")


def run(scenario: Scenario, n_frames: int = 60, range_window_m: tuple[float, float] | None = (1.0, 30.0),
        altitude_m: float = 2.0, *, without_truth: bool = True, baseline: bool | None = None) -> dict:
    """Render ``n_frames`` frames and report throughput.

    ``range_window_m`` is clipped to the sonar preset's range limits (a short-range sonar
    such as the ARIS 3000 renders its own window); None keeps the scenario's window.

    ``without_truth`` False renders only the pass with the ground truth (callers that hook
    :meth:`FlsSensor.render` to see the bench's frames once each).

    Returns:
        dict with ``frames_per_s``, ``ms_per_frame`` (wall clock), ``cpu_ms_per_frame`` and
        ``cpu_frames_per_s`` (process CPU time, all threads: steadier on a shared machine), ``rays_per_s`` (all rays cast, edge
        refinement and occlusion casts included, per second of total frame time),
        ``raw_raycast_fraction`` (time inside ``mj_multiRay`` calls / total),
        ``n_rays`` (base rays per frame), ``rays_cast_per_frame``, ``n_beams``, ``n_bins``,
        ``visible_objects`` (mean per frame); ``baseline`` (see the module; None: only when the
        scenario's sonar uses the counter-based speckle): ``before``, ``scenario`` and
        ``embree`` (when installed), each ``cpu_ms_per_frame``, ``cpu_frames_per_s`` and
        ``speedup_cpu``; ``no_truth`` the same frames rendered without the
        ground truth (``frames_per_s``, ``ms_per_frame``, ``cpu_ms_per_frame``,
        ``cpu_frames_per_s``, ``identical_frames``: the fan and polar images of the first
        :data:`IDENTITY_FRAMES` frames byte-identical with and without the truth, rendered
        again untimed from fresh noise states).
    """
    check_scenario(scenario)
    base = scenario.sensors.fls
    if range_window_m is not None:
        p = PRESETS[base.preset]
        lo, hi = base.range_min_m or p.range_min_m, base.range_max_m or p.range_max_m
        near, far = max(range_window_m[0], lo), min(range_window_m[1], hi)
        base = FlsConfig(**{**base.model_dump(), "range_window_m": (near, far) if near < far else None})
    cfg = base
    world = build_world(scenario)
    caster = _TimedCaster(MujocoRayCaster(world.model, world.data, world.geom_object_id, world.geom_reflectivity,
                                          world.vehicle_body_id, backend=scenario.physics.ray_caster))
    mount = world.site_pos_body(cfg.mount_site) if cfg.mount_site in world.site_ids else np.zeros(3)
    sensor = FlsSensor(cfg, mount, component_rng(scenario.seed, "fls"))

    # survey pose: west of the targets' centre, heading east along the rows, at altitude
    centroids = np.array([o.centroid_ned for o in world.objects]) if world.objects else np.zeros((1, 3))
    seabed_z = float(world.seabed.depth_at(*centroids[:, :2].mean(axis=0)))
    start = np.array([centroids[:, 0].mean(), centroids[:, 1].min() - 6.0, seabed_z - altitude_m])
    R_nb = rot_from_euler(0.0, 0.0, np.pi / 2)

    def pose(i: int) -> np.ndarray:  # creep forward 0.5 m/s at 3 Hz, like a survey leg
        return start + np.array([0.0, 0.5 / 3.0 * i, 0.0]) + R_nb @ mount

    sensor.render(0.0, pose(0), R_nb, caster, world.objects)  # warm-up
    caster.time_s, caster.n_rays = 0.0, 0
    visible = 0
    t0, c0 = time.perf_counter(), time.process_time()
    for i in range(n_frames):
        out = sensor.render(i / 3.0, pose(i), R_nb, caster, world.objects)
        visible += sum(o.visible for o in out.truth.objects)
    total = time.perf_counter() - t0
    cpu = time.process_time() - c0
    ray_time_s, n_rays = caster.time_s, caster.n_rays
    g = sensor.geometry
    result = {
        "frames_per_s": round(n_frames / total, 2),
        "ms_per_frame": round(1e3 * total / n_frames, 3),
        "cpu_ms_per_frame": round(1e3 * cpu / n_frames, 3),
        "cpu_frames_per_s": round(n_frames / cpu, 2),
        "rays_per_s": round(n_rays / total),
        "raw_raycast_fraction": round(ray_time_s / total, 4),
        "n_rays": sensor.n_rays,
        "rays_cast_per_frame": round(n_rays / n_frames),
        "n_beams": g.n_beams,
        "n_bins": g.n_bins,
        "range_window_m": [g.window_near_m, g.window_far_m],
        "preset": cfg.preset,
        "visible_objects": round(visible / n_frames, 2),
        "n_frames": n_frames,
    }
    if baseline is None:
        baseline = cfg.speckle_generator == "counter"
    if baseline:
        result["baseline"] = _against_before(scenario, cfg, mount, pose, R_nb, world, n_frames)
    if without_truth:
        result["no_truth"] = _without_truth(scenario, cfg, mount, pose, R_nb, caster, world.objects, n_frames)
    return result


BASELINE_ROUNDS = 3  # rounds of the renderers compared, interleaved


def _against_before(scenario: Scenario, cfg: FlsConfig, mount: np.ndarray, pose, R_nb: np.ndarray, world,
                    n_frames: int) -> dict:
    """CPU per frame of the bench's frames by the renderer before, the scenario's and the
    scenario's with Embree, in :data:`BASELINE_ROUNDS` interleaved rounds (with the ground truth)."""
    def caster(backend: str) -> MujocoRayCaster:
        return MujocoRayCaster(world.model, world.data, world.geom_object_id, world.geom_reflectivity,
                               world.vehicle_body_id, backend=backend)

    variants = {"before": (cfg.model_copy(update={"speckle_generator": "stream"}), caster("mujoco")),
                "scenario": (cfg, caster(scenario.physics.ray_caster))}
    if embree_available() and scenario.physics.ray_caster != "embree":
        variants["embree"] = (cfg, caster("embree"))
    sensors = {name: (FlsSensor(c, mount, component_rng(scenario.seed, "fls")), cast)
               for name, (c, cast) in variants.items()}
    cpu = dict.fromkeys(sensors, 0.0)
    for s, cast in sensors.values():
        s.render(0.0, pose(0), R_nb, cast, world.objects)  # warm-up
    for _ in range(BASELINE_ROUNDS):
        for name, (s, cast) in sensors.items():
            c0 = time.process_time()
            for i in range(n_frames):
                s.render(i / 3.0, pose(i), R_nb, cast, world.objects)
            cpu[name] += time.process_time() - c0
    n = BASELINE_ROUNDS * n_frames
    return {name: {"cpu_ms_per_frame": round(1e3 * c / n, 3), "cpu_frames_per_s": round(n / c, 2),
                   "speedup_cpu": round(cpu["before"] / c, 3)} for name, c in cpu.items()}


def _without_truth(scenario: Scenario, cfg: FlsConfig, mount: np.ndarray, pose, R_nb: np.ndarray, caster,
                   objects, n_frames: int) -> dict:
    """The bench's frames rendered without the ground truth from a fresh noise state (timed),
    then the first :data:`IDENTITY_FRAMES` again with and without it (untimed, compared)."""
    def sensor() -> FlsSensor:
        return FlsSensor(cfg, mount, component_rng(scenario.seed, "fls"))

    bare = sensor()
    bare.render_truth = False
    bare.render(0.0, pose(0), R_nb, caster, objects)  # warm-up, as the first pass
    t1, c1 = time.perf_counter(), time.process_time()
    for i in range(n_frames):
        bare.render(i / 3.0, pose(i), R_nb, caster, objects)
    total = time.perf_counter() - t1
    cpu = time.process_time() - c1
    # frames are not kept in the timed loops: holding them makes every frame's arrays fresh pages
    full, lean = sensor(), sensor()
    lean.render_truth = False
    same = True
    for i in range(min(n_frames, IDENTITY_FRAMES) + 1):
        a = full.render(i / 3.0, pose(i), R_nb, caster, objects).frame
        b = lean.render(i / 3.0, pose(i), R_nb, caster, objects).frame
        same &= np.array_equal(a.fan, b.fan) and np.array_equal(a.polar, b.polar)
    return {"frames_per_s": round(n_frames / total, 2), "ms_per_frame": round(1e3 * total / n_frames, 3),
            "cpu_ms_per_frame": round(1e3 * cpu / n_frames, 3), "cpu_frames_per_s": round(n_frames / cpu, 2),
            "identical_frames": bool(same)}
