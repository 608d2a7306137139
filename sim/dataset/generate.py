"""``auvsim dataset``: domain-randomised, labelled FLS frames (or side-scan tiles,
:mod:`sim.dataset.sss_generate`, with the same layout, resume and determinism).

Layout of an output directory::

    manifest.json        generator version, seed, every parameter; ``complete`` once merged
    images/000001.png    fan images (8-bit grey)
    parts/scene_00000.json  per-scene labels, written atomically after the scene's images
    annotations.json     COCO detection file (RLE instance masks, fan geometry per image)
    labels/000001.txt    YOLO labels (class cx cy w h, normalised)

Work is split into scenes (one compiled world, several sonar poses). A scene counts as
done when its part file exists, so an interrupted run resumes where it stopped and a
finished dataset is identical to an uninterrupted one. Frames depend only on (seed,
scene index), never on the number of workers. Local workers on Linux are forked after the
parent has rendered one scene, so they start with its imports and loaded kernels
(:func:`_run_local`).
"""

from __future__ import annotations

import gc
import json
import math
import os
import signal
import sys
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from scenarios.config.fls import FlsConfig
from sim.dataset.coco_io import (ANNOTATIONS_FILE, IMAGES_DIR, LABELS_DIR, fan_geometry_record, write_atomic, write_coco,
                                 write_png_atomic,
                                 yolo_lines)
from sim.dataset.errors import DatasetError
from sim.dataset.sss_generate import SssRandomization, SssSettings
from sim.dataset.tank_generate import TankSettings
from sim.dataset.randomization import (RANDOMIZATION_PRESETS, TRAIN_RANDOMIZATION,  # noqa: F401 (presets re-exported)
                                      CLASS_NAMES, Randomization, SceneSpec, draw_world_seed_and_seabed_kind,
                                      sample_scene, seabed_depth_fn)
from sim.outputs.run_dir import check_output_dir, write_marker
from sim.rng import component_rng
from sim.process.spawn_guard import exit_if_spawn_reimport, main_guard_missing
from sim.process.worker_signals import ignore_sigint, sigint_blocked

GENERATOR_VERSION = "1.4.0"  # 1.4.0: Rayleigh speckle from the counter-based generator (other frames, same labels)
MANIFEST_FILE = "manifest.json"
PARTS_DIR = "parts"
RAY_HINT = "--ray needs Ray: pip install 'auvsim[scale]' (or pip install ray)"


@dataclass(frozen=True)
class RenderSettings:
    """Sonar settings common to all frames (the rest is randomised per scene).

    ``min_visible_fraction`` and ``min_area_px``: objects below either are labelled
    ``iscrowd`` (present but not expected to be detected; ignored by the evaluation).
    """

    preset: str = "m900_130"
    elevation_rays: int = 16
    azimuth_columns: int | None = 361
    min_visible_fraction: float = 0.3
    min_area_px: int = 12


def scene_spec(seed: int, index: int, rz: Randomization) -> SceneSpec:
    """The scene ``index`` of a dataset with root ``seed`` (depends on nothing else)."""
    return sample_scene(index, component_rng(seed, f"dataset/scene/{index}"), rz, seabed_depth_fn)


def fls_config(spec: SceneSpec, settings: RenderSettings) -> FlsConfig:
    base = FlsConfig()
    return FlsConfig(preset=settings.preset, tilt_deg=float(np.rad2deg(spec.tilt_rad)),
                     range_window_m=(spec.range_min_m, spec.range_max_m), elevation_rays=settings.elevation_rays,
                     azimuth_columns=settings.azimuth_columns, gain_db=base.gain_db + spec.gain_db,
                     noise_floor_db=base.noise_floor_db + 10.0 * math.log10(spec.noise_scale),
                     speckle=spec.speckle, k_shape=spec.k_shape)


def render_scene(spec: SceneSpec, seed: int, settings: RenderSettings, frame_ids: list[int],
                 out_dir: Path) -> dict:
    """Render the frames of one scene, write their PNGs; return the scene's label part."""

    from sim.dataset.scene_render import render_frames

    records = render_frames(spec, fls_config(spec, settings), component_rng(seed, f"dataset/fls/{spec.index}"),
                            len(frame_ids))
    images, annotations = [], []
    for frame_id, rec in zip(frame_ids, records):
        name = f"{IMAGES_DIR}/{frame_id:06d}.png"
        write_png_atomic(out_dir / name, rec.fan)
        g = rec.geometry
        images.append({
            "id": frame_id, "file_name": name, "width": int(rec.fan.shape[1]), "height": int(rec.fan.shape[0]),
            "scene": spec.index, "t_s": rec.t_s,
            "fan_geometry": fan_geometry_record(g),
            "sonar": {"pos_ned": list(rec.pos_ned), "rpy_rad": list(rec.rpy_rad), "tilt_rad": spec.tilt_rad,
                      "altitude_m": rec.altitude_m, "seabed": spec.seabed.kind, "gain_db": spec.gain_db,
                      "noise_scale": spec.noise_scale, "speckle": spec.speckle},
        })
        for obj in rec.objects:
            crowd = obj.visible_fraction < settings.min_visible_fraction or obj.area_px < settings.min_area_px
            annotations.append({
                "image_id": frame_id, "category_id": CLASS_NAMES.index(obj.class_name) + 1,
                "bbox": obj.bbox_coco, "area": obj.area_px, "segmentation": obj.rle, "iscrowd": int(crowd),
                "attributes": {"object": obj.name, "shape": obj.shape, "is_target": obj.is_target,
                               "visible_fraction": obj.visible_fraction, "range_m": obj.range_m,
                               "azimuth_rad": obj.azimuth_rad, "pos_ned": list(obj.pos_ned)},
            })
    return {"scene": spec.index, "images": images, "annotations": annotations}


def _scene_job(job: tuple) -> int:
    seed, index, rz_json, settings, frame_ids, out_dir = job
    out_dir = Path(out_dir)
    if isinstance(settings, SssSettings):
        from sim.dataset.sss_generate import render_sss_scene, sss_scene_spec

        rz_sss = SssRandomization.model_validate_json(rz_json)
        part = render_sss_scene(sss_scene_spec(seed, index, rz_sss, settings), seed, settings, frame_ids, out_dir)
    elif isinstance(settings, TankSettings):
        from sim.dataset.tank_generate import render_tank_scene

        part = render_tank_scene(seed, index, settings, frame_ids, out_dir)
    else:
        rz = Randomization.model_validate_json(rz_json)
        part = render_scene(scene_spec(seed, index, rz), seed, settings, frame_ids, out_dir)
    write_atomic(out_dir / PARTS_DIR / f"scene_{index:05d}.json", json.dumps(part))
    return len(frame_ids)


def _manifest(n_frames: int, seed: int, rz, settings: RenderSettings | SssSettings | TankSettings) -> dict:
    """The manifest of a dataset: ``randomization`` holds the ranges its scenes were drawn
    from (a side-scan dataset's :class:`~sim.dataset.sss_generate.SssRandomization`, ``rz``
    as passed for FLS frames)."""
    if isinstance(settings, TankSettings):
        return {"generator_version": GENERATOR_VERSION, "sensor": "fls", "scene": "tank", "seed": seed,
                "n_frames": n_frames, "classes": list(settings.classes), "formats": list(settings.spec.formats),
                "spec": settings.spec.model_dump(mode="json"), "fls_defaults": FlsConfig().model_dump(mode="json")}
    rz_json = rz.model_dump(mode="json")
    if rz_json.get("basin") is None:
        rz_json.pop("basin", None)  # datasets without basin walls keep their earlier manifests
    if isinstance(settings, SssSettings):
        from scenarios.config.sss import SssConfig

        return {"generator_version": GENERATOR_VERSION, "sensor": "sss", "seed": seed, "n_frames": n_frames,
                "classes": list(CLASS_NAMES), "randomization": rz_json, "render": settings.__dict__.copy(),
                "sss_defaults": SssConfig().model_dump(mode="json")}
    return {"generator_version": GENERATOR_VERSION, "seed": seed, "n_frames": n_frames,
            "classes": list(CLASS_NAMES), "randomization": rz_json,
            "render": settings.__dict__.copy(), "fls_defaults": FlsConfig().model_dump(mode="json")}


def merge_parts(out_dir: Path, manifest: dict) -> None:
    """Collect the per-scene parts into ``annotations.json`` and YOLO labels."""
    parts = sorted((out_dir / PARTS_DIR).glob("scene_*.json"))
    images, annotations = [], []
    for p in parts:
        part = json.loads(p.read_text())
        images.extend(part["images"])
        annotations.extend(part["annotations"])
    images.sort(key=lambda r: r["id"])
    annotations.sort(key=lambda a: (a["image_id"], a["attributes"]["object"]))
    for i, a in enumerate(annotations, start=1):
        a["id"] = i
    classes = manifest.get("classes", list(CLASS_NAMES))
    if manifest.get("scene") == "tank":
        categories = [{"id": i + 1, "name": n, "supercategory": "structure" if n == "Wall" else "object"}
                      for i, n in enumerate(classes)]
    else:
        categories = [{"id": i + 1, "name": n, "supercategory": "target" if i == 0 else "clutter"}
                      for i, n in enumerate(classes)]
    write_atomic(out_dir / "classes.txt", "\n".join(classes) + "\n")
    info = {"description": "auvsim synthetic FLS ATR dataset", "version": GENERATOR_VERSION,
            "seed": manifest["seed"]}
    if manifest.get("sensor") == "sss":
        info = {**info, "description": "auvsim synthetic side-scan (SSS) tile dataset", "sensor": "sss"}
    if manifest.get("scene") == "tank":
        info = {**info, "description": f"auvsim synthetic FLS tank frames, spec {manifest['spec']['name']}"}
    if "yolo" not in manifest.get("formats", ("yolo",)):
        write_coco(out_dir / ANNOTATIONS_FILE, images, annotations, categories, info)
        return
    (out_dir / LABELS_DIR).mkdir(exist_ok=True)
    by_image: dict[int, list[dict]] = {}
    for a in annotations:
        if not a["iscrowd"]:
            by_image.setdefault(a["image_id"], []).append(a)
    for im in images:
        anns = by_image.get(im["id"], [])
        txt = yolo_lines(np.array([a["bbox"] for a in anns]).reshape(-1, 4),
                         np.array([a["category_id"] - 1 for a in anns]), im["width"], im["height"])
        write_atomic(out_dir / LABELS_DIR / f"{im['id']:06d}.txt", txt)
    write_coco(out_dir / ANNOTATIONS_FILE, images, annotations, categories, info)


def _frames_per_scene(settings, randomization) -> int:
    """Frames (side-scan: tiles) one scene gives under ``settings``."""
    return (settings.tiles_per_scene() if isinstance(settings, SssSettings) else
            settings.frames_per_scene if isinstance(settings, TankSettings) else randomization.frames_per_scene)


def _extend(out_dir: Path, old_n: int, settings, randomization) -> None:
    """Prepare ``out_dir`` to grow from ``old_n`` frames: scene ``k`` depends on the seed and
    ``k`` alone, so the scenes already written stay; a last scene cut short by ``old_n`` is
    rendered again whole (its part file removed; its frames come out the same)."""
    fps = _frames_per_scene(settings, randomization)
    if old_n % fps:
        (out_dir / PARTS_DIR / f"scene_{old_n // fps:05d}.json").unlink(missing_ok=True)


def generate_dataset(out_dir: str | Path, n_frames: int, seed: int = 0, workers: int | None = None,
                     ray_address: str | None = None, use_ray: bool = False,
                     randomization: Randomization | SssRandomization = TRAIN_RANDOMIZATION,
                     settings: RenderSettings | SssSettings | TankSettings = RenderSettings(),
                     progress: bool = True) -> Path:
    """Write (or finish) a dataset of ``n_frames`` frames in ``out_dir``; returns the COCO file.

    ``settings``: :class:`RenderSettings` for FLS fan images, a
    :class:`sim.dataset.tank_generate.TankSettings` for a tank spec's frames
    (``randomization`` unused), :class:`SssSettings` for side-scan tiles (``n_frames`` tiles, ``settings.tiles_per_scene()`` per scene; their
    ranges are :func:`sim.dataset.sss_generate.sss_randomization` of ``randomization``, which
    may also be an ``SssRandomization``).
    ``workers``: local processes (default: all cores; 1 = in this process). ``use_ray``:
    distribute scenes with Ray (``ray_address`` None starts a local instance). A folder
    holding the same dataset with fewer frames grows to ``n_frames`` (its frames kept: scene
    ``k`` depends on the seed and ``k`` alone).

    Raises:
        DatasetError: ``n_frames`` < 1, side-scan settings out of range (a tile longer than
            the line), ``out_dir`` holds a dataset made with other parameters or more frames, or (where workers
            are spawned: macOS, Windows) ``workers`` > 1 from a main script without the
            ``if __name__ == "__main__":`` guard (:mod:`sim.process.spawn_guard`).
        OutputDirError: ``out_dir`` is protected, a file, not creatable, or holds files
            that are not an auvsim dataset.
        ImportError: ``use_ray`` without Ray installed (message :data:`RAY_HINT`), before
            anything is created.
    """
    exit_if_spawn_reimport()  # a spawned worker re-running an unguarded script: nothing written
    if n_frames < 1:
        raise DatasetError(f"--n: must be >= 1, got {n_frames}")
    if isinstance(settings, SssSettings):
        from sim.dataset.sss_generate import sss_randomization

        settings.check()
        randomization = sss_randomization(randomization, settings)  # what the side-scan scenes draw from
    if use_ray:
        _import_ray()  # before the output folder or a progress bar exists
    out_dir = check_output_dir(out_dir, kind="dataset", resume=True)
    (out_dir / IMAGES_DIR).mkdir(parents=True, exist_ok=True)
    (out_dir / PARTS_DIR).mkdir(exist_ok=True)
    manifest = _manifest(n_frames, seed, randomization, settings)
    man_path = out_dir / MANIFEST_FILE
    if man_path.is_file():
        try:
            old = json.loads(man_path.read_text())
            if not isinstance(old, dict):
                raise ValueError("not a JSON object")
        except (OSError, UnicodeDecodeError, ValueError) as exc:
            raise DatasetError(f"--out {out_dir}: its {MANIFEST_FILE} is damaged ({exc}); use a new --out folder") from None
        old.pop("complete", None)
        diff = sorted(k for k in set(old) | set(manifest) if old.get(k) != manifest.get(k))
        if diff == ["n_frames"] and isinstance(old.get("n_frames"), int) and old["n_frames"] < n_frames:
            _extend(out_dir, old["n_frames"], settings, randomization)
        elif diff == ["n_frames"]:
            raise DatasetError(f"--n {n_frames}: below the {old.get('n_frames')} frames {out_dir} already holds "
                               "(a dataset grows, it is not cut); use a new --out folder")
        elif diff:
            raise DatasetError(f"--out {out_dir}: holds a dataset made with other parameters "
                               f"(differs in {', '.join(diff)}); use a new --out folder")
    write_atomic(man_path, json.dumps({**manifest, "complete": False}, indent=1))
    write_marker(out_dir, "dataset")
    if isinstance(settings, TankSettings) and "watertank" in settings.spec.formats:
        from sim.dataset.tank_generate import BOXES_DIR, MASKS_DIR

        (out_dir / BOXES_DIR).mkdir(exist_ok=True)
        (out_dir / MASKS_DIR).mkdir(exist_ok=True)
    fps = _frames_per_scene(settings, randomization)
    n_scenes = math.ceil(n_frames / fps)
    rz_json = randomization.model_dump_json()
    jobs = []
    for k in range(n_scenes):
        if (out_dir / PARTS_DIR / f"scene_{k:05d}.json").is_file():
            continue
        ids = list(range(k * fps + 1, min((k + 1) * fps, n_frames) + 1))
        jobs.append((seed, k, rz_json, settings, ids, str(out_dir)))
    total = sum(len(j[4]) for j in jobs)
    from tqdm import tqdm

    bar = tqdm(total=total, unit="frame", desc="dataset", disable=not progress or total == 0)
    try:
        if use_ray:
            _run_ray(jobs, ray_address, bar)
        else:
            _run_local(jobs, workers or os.cpu_count() or 1, bar)
    finally:
        bar.close()
    merge_parts(out_dir, manifest)
    write_atomic(man_path, json.dumps({**manifest, "complete": True}, indent=1))
    return out_dir / ANNOTATIONS_FILE


def worker_modules(settings: RenderSettings | SssSettings | TankSettings) -> tuple[str, ...]:
    """Modules a scene job imports beyond this one (lazily: a process that renders nothing skips them)."""
    shared = ("cv2", "scenarios.schema", "sim.sensors.raycast", "sim.scene.world", "sim.scene.seabed",
              "sim.scene.target_meshes")
    if isinstance(settings, SssSettings):
        return shared + ("scenarios.config.sss", "sim.dataset.sss_generate", "sim.sensors.sss", "sim.dataset.sss_tiles")
    if isinstance(settings, TankSettings):
        return shared + ("sim.dataset.tank_generate", "sim.dataset.tank_scenes", "sim.sensors.fls")
    return shared + ("sim.dataset.scene_render", "sim.sensors.fls")


def _worker_init() -> None:
    """A worker ends on SIGTERM (the pool's shutdown) as a spawned one does, whatever handler
    a forked one inherited (``auvsim``'s turns SIGTERM into an exception), and ignores Ctrl-C:
    the terminal sends SIGINT to the whole process group, and the parent, which handles it,
    ends the pool (a worker raising ``KeyboardInterrupt`` would print a traceback). SIGINT
    stays blocked from before the fork (:func:`_worker_pool`) until it is ignored here
    (:mod:`sim.process.worker_signals`), so no Ctrl-C lands in between."""
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    ignore_sigint()


@contextmanager
def _worker_pool(start_method: str, n_processes: int):
    """A ``multiprocessing`` pool of ``n_processes`` started by ``start_method``, its workers
    ignoring Ctrl-C; terminated when the block ends, also when a Ctrl-C held back while it
    started is delivered."""
    import multiprocessing as mp

    with ExitStack() as stack:
        with sigint_blocked():
            pool = stack.enter_context(mp.get_context(start_method).Pool(n_processes, initializer=_worker_init))
        yield pool


@contextmanager
def _opencv_single_threaded():
    """OpenCV without its worker threads while this block runs (its previous thread count after).

    A forked child keeps only the forking thread; OpenCV's pthreads pool would still count the
    parent's workers (and a mutex one of them held at the fork would stay locked). With one
    thread OpenCV joins its workers and runs every ``parallel_for`` inline; each output pixel
    is computed the same way either way, so the images are unchanged.
    """
    import cv2

    previous = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        yield
    finally:
        cv2.setNumThreads(previous)


def _builds_terrain_mesh(job: tuple) -> bool:
    """Whether an FLS scene job's seabed is a terrain mesh (a few times the work of a flat one:
    the mesh to build and compile); side-scan jobs count as flat (their order is kept)."""
    seed, index, rz_json, settings = job[:4]
    if isinstance(settings, (SssSettings, TankSettings)):
        return False
    rz = Randomization.model_validate_json(rz_json)
    _, kind = draw_world_seed_and_seabed_kind(component_rng(seed, f"dataset/scene/{index}"), rz)
    return kind in ("rough", "ripple")


def _run_local(jobs: list[tuple], n_workers: int, bar) -> None:
    """Render ``jobs`` in this process (one worker) or in a pool of ``n_workers`` processes.

    On Linux this process renders one scene itself, a flat-bed one if there is one (the workers
    wait for it), then forks the workers: they inherit the imports and the loaded compiled
    kernels (about 0.4 s of imports and 0.45 s of first-frame set-up a spawned worker pays
    again, each). The pool takes the terrain-mesh scenes first, so the last scenes, which one
    worker may finish while the others idle, are the short ones. Elsewhere (macOS, Windows:
    fork unsafe or absent) the workers are spawned. Frames depend only on (seed, scene index),
    so every way and order gives the same files.
    """
    if n_workers <= 1 or len(jobs) <= 1:
        for job in jobs:
            bar.update(_scene_job(job))
        return
    heavy = [_builds_terrain_mesh(j) for j in jobs]
    jobs = [j for j, h in zip(jobs, heavy) if h] + [j for j, h in zip(jobs, heavy) if not h]  # stable
    if not sys.platform.startswith("linux"):
        import multiprocessing as mp

        if main_guard_missing(mp.get_context("spawn")):
            raise DatasetError(f"workers={n_workers}: the worker processes start with spawn here, which runs the "
                               "main script again; create the dataset under if __name__ == \"__main__\": "
                               "(or use workers=1)")
        with _worker_pool("spawn", min(n_workers, len(jobs))) as pool:
            for done in pool.imap_unordered(_scene_job, jobs):
                bar.update(done)
        return
    with _opencv_single_threaded():
        bar.update(_scene_job(jobs[-1]))
        rest = jobs[:-1]
        if len(rest) <= 1:
            for job in rest:
                bar.update(_scene_job(job))
            return
        gc.freeze()  # what the children inherit stays out of their collections (and its pages shared)
        try:
            with _worker_pool("fork", min(n_workers, len(rest))) as pool:
                for done in pool.imap_unordered(_scene_job, rest):
                    bar.update(done)
        finally:
            gc.unfreeze()


def _import_ray():
    """The ``ray`` module. Raises ImportError(:data:`RAY_HINT`) where it is not installed."""
    try:
        import ray
    except ImportError as exc:
        raise ImportError(RAY_HINT) from exc
    return ray


def _run_ray(jobs: list[tuple], address: str | None, bar) -> None:
    ray = _import_ray()
    started = False
    if not ray.is_initialized():
        ray.init(address=address, include_dashboard=False, log_to_driver=False)
        started = True
    try:
        remote = ray.remote(_scene_job)
        pending = [remote.remote(j) for j in jobs]
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            bar.update(ray.get(done[0]))
    finally:
        if started:
            ray.shutdown()


def generation_args(spec) -> dict:
    """The ``randomization`` and ``settings`` arguments of :func:`generate_dataset` for a
    :class:`sim.dataset.spec.DatasetSpec`."""
    if spec.scene.kind == "tank":
        return {"settings": TankSettings(spec.model_dump_json())}
    rays = spec.sonar.elevation_rays
    return {"randomization": spec.scene.build(),
            "settings": RenderSettings(preset=spec.sonar.preset,
                                       elevation_rays=RenderSettings.elevation_rays if rays is None else rays,
                                       azimuth_columns=spec.sonar.azimuth_columns,
                                       min_visible_fraction=spec.labels.min_visible_fraction,
                                       min_area_px=spec.labels.min_area_px)}
