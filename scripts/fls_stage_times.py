"""CPU milliseconds per FLS frame by render stage, on the ``auvsim bench fls`` pose sequence.

Wraps the stages of :meth:`sim.sensors.fls.FlsSensor.render` with process-time counters
(steadier than wall time on a shared machine), renders ``--frames`` frames after a short
warm-up and prints one JSON object: ``render`` (the whole frame) and each stage's ms per
frame. Nested entries (``bisect``, ``same_surface`` and ``mj_multiRay`` inside
``refine_edges``/``cast``, ``visible_fraction`` inside ``objects_truth``) are not added to
``other``.

``--dataset-scenes N`` times the dataset generator's renders instead: the first
``--dataset-frames`` frames of scenes ``0..N-1`` of each randomization preset (rough and
rippled mesh seabeds, more objects), through :func:`sim.dataset.scene_render.render_frames`
(scene builds excluded: only the wrapped stages and ``render`` are counted).

Usage: ``python scripts/fls_stage_times.py [--frames 150] [--scenario cssn_lawnmower]
[--dataset-scenes 4 --dataset-frames 4]``
"""

from __future__ import annotations

import argparse
import json
import time
from collections import defaultdict

STAGES = {  # label: (module, attribute path)
    "cast": ("sim.sensors.sonar.ray_fan", "RayFan.cast"),
    "object_rays": ("sim.sensors.fls", "FlsSensor._add_object_rays"),
    "refine_edges": ("sim.sensors.sonar.ray_fan", "RayFan.refine_edges"),
    "ray_strength": ("sim.sensors.fls", "ray_strength"),
    "range_slope": ("sim.sensors.sonar.ray_fan", "RayFan.range_slope"),
    "echo_segments": ("sim.sensors.fls", "echo_segments"),
    "echo_lines": ("sim.sensors.sonar.echo_lines", "EchoSegments.lines"),
    "mean_intensity": ("sim.sensors.fls", "EchoChain.mean_intensity"),
    "labels": ("sim.sensors.fls", "label_bins"),
    "resize": ("sim.sensors.fls", "cv2.resize"),
    "speckle": ("sim.sensors.fls", "EchoChain.realise"),
    "db_display": ("sim.sensors.fls", "EchoChain.display"),
    "fan_remap": ("sim.sensors.fls", "FanRemap.image"),
    "objects_truth": ("sim.sensors.fls", "FlsSensor._objects_truth"),
}
NESTED = {  # counted inside a stage above
    "bisect": ("sim.sensors.sonar.ray_fan", "RayFan.bisect"),
    "mj_multiRay": ("sim.sensors.raycast", "MujocoRayCaster._raw"),
    "visible_fraction": ("sim.sensors.fls", "visible_fraction"),
    "same_surface": ("sim.sensors.sonar.ray_fan", "same_surface_rows"),
}


def _wrap(totals: defaultdict, label: str, module: str, path: str) -> None:
    import importlib

    owner = importlib.import_module(module)
    *parents, name = path.split(".")
    for p in parents:
        owner = getattr(owner, p)
    inner = getattr(owner, name)

    def timed(*args, **kwargs):
        t0 = time.process_time()
        try:
            return inner(*args, **kwargs)
        finally:
            totals[label] += time.process_time() - t0

    setattr(owner, name, timed)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=150)
    ap.add_argument("--scenario", default="cssn_lawnmower")
    ap.add_argument("--dataset-scenes", type=int, default=0)
    ap.add_argument("--dataset-frames", type=int, default=4)
    args = ap.parse_args()

    from scenarios.load import load_scenario
    from sim.bench import fls as bench_fls

    totals: defaultdict = defaultdict(float)
    for label, (module, path) in {**STAGES, **NESTED, "render": ("sim.sensors.fls", "FlsSensor.render")}.items():
        _wrap(totals, label, module, path)
    scenario = load_scenario(args.scenario)
    bench_fls.run(scenario, 3, without_truth=False, baseline=False)  # imports, compiled kernels, caches
    totals.clear()
    if args.dataset_scenes > 0:
        n = _dataset_frames(args.dataset_scenes, args.dataset_frames)
        extra = {"dataset_scenes": args.dataset_scenes, "cpu_frames_per_s": round(n / totals["render"], 2)}
    else:
        result = bench_fls.run(scenario, args.frames, without_truth=False, baseline=False)
        n = args.frames + 1  # the bench's own warm-up frame is timed too
        extra = {"cpu_frames_per_s": result["cpu_frames_per_s"]}
    ms = {k: round(1e3 * v / n, 3) for k, v in sorted(totals.items(), key=lambda kv: -kv[1])}
    ms["other"] = round(ms["render"] - sum(ms.get(k, 0.0) for k in STAGES), 3)
    print(json.dumps({"ms_per_frame": ms, **extra, "frames": n}))


def _dataset_frames(n_scenes: int, n_frames: int) -> int:
    """Render the first ``n_frames`` frames of scenes ``0..n_scenes-1`` of every randomization
    preset (dataset seed 0); returns the number of frames rendered."""
    from sim.dataset.generate import RANDOMIZATION_PRESETS, RenderSettings, fls_config, scene_spec
    from sim.dataset.scene_render import render_frames
    from sim.rng import component_rng

    n = 0
    for rz in RANDOMIZATION_PRESETS.values():
        for i in range(n_scenes):
            spec = scene_spec(0, i, rz)
            n += len(render_frames(spec, fls_config(spec, RenderSettings()), component_rng(0, f"dataset/fls/{i}"),
                                   n_frames))
    return n


if __name__ == "__main__":
    main()
