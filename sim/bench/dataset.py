"""``auvsim bench dataset``: labelled FLS dataset frames per second, one worker against N.

Each configuration runs the way a user pays for it: a fresh ``auvsim dataset`` process
(``python -m sim.cli dataset --n N_FRAMES --workers W``) writing into a new temporary folder,
start-up (imports, numba cache load, starting the worker processes: on Linux forked after the
parent rendered the first scene, elsewhere spawned) and the final merge of the labels included.
Wall time is the process's; CPU time is that of the process and every worker process it started
(``resource.getrusage(RUSAGE_CHILDREN)``: each worker is reaped by the pool, so its time reaches
the dataset process and then this one, with no sampling gap). The two runs are timed in the
same call, so a busy machine slows both alike: read ``workers_speedup`` (one worker's wall time
over N's) and ``cpu_frames_per_s`` (frames per CPU second, all processes: what each core gives).

Start-up is reported separately (``startup``): the wall and CPU time of a fresh interpreter
importing what a dataset worker imports (:func:`sim.dataset.generate.worker_modules`) and
rendering nothing (the first frame's set-up, numba's load of the cached sonar kernels and
the renderer's lazy imports, about 0.45 s CPU more, is not in it; it is in the runs, once per
process that renders). The frames of both runs are compared byte for byte
(``identical_across_workers``): a dataset does not depend on the number of workers.
"""

from __future__ import annotations

import hashlib
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

N_FRAMES = 96  # 24 scenes of 4 frames: about 10-20 s for both runs together on an idle 2-core machine
WORKER_IMPORTS = ("import importlib, sim.dataset.generate as g\n"
                  "for name in g.worker_modules(g.RenderSettings()):\n    importlib.import_module(name)")


def _children_cpu_s() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def _timed(cmd: list[str]) -> tuple[float, float]:
    """(wall s, CPU s of the process and all its reaped descendants) of running ``cmd``.

    Raises:
        RuntimeError: the command failed (its stderr's last line attached).
    """
    c0, t0 = _children_cpu_s(), time.perf_counter()
    out = subprocess.run(cmd, capture_output=True, text=True, cwd=Path(__file__).resolve().parents[2])
    wall, cpu = time.perf_counter() - t0, _children_cpu_s() - c0
    if out.returncode != 0:
        last = (out.stderr.strip().splitlines() or ["(no output)"])[-1]
        raise RuntimeError(f"{' '.join(cmd)} exited {out.returncode}: {last}")
    return wall, cpu


def _images_digest(out_dir: Path) -> str:
    h = hashlib.sha256()
    for p in sorted((out_dir / "images").glob("*.png")):
        h.update(p.name.encode())
        h.update(p.read_bytes())
    return h.hexdigest()


def run(seed: int = 0, workers: int | None = None, n_frames: int = N_FRAMES) -> dict[str, Any]:
    """Dataset throughput with one worker and with ``workers`` (default: all cores) in one run.

    Args:
        seed: the dataset's root seed.
        workers: worker processes of the second run (>= 1; 1 repeats the one-worker run).
        n_frames: labelled frames per run (4 per scene).

    Returns:
        dict with ``n_frames``, ``workers``, ``one_worker`` and ``n_workers`` (each:
        ``wall_s``, ``cpu_s``, ``frames_per_s`` wall, ``cpu_frames_per_s`` per CPU second of
        all processes), ``workers_speedup`` (wall, one worker over N), ``cpu_per_frame_ratio``
        (N workers' CPU per frame over one worker's: the start-up each extra worker adds),
        ``startup`` (``wall_s``, ``cpu_s`` of one fresh worker's imports) and
        ``identical_across_workers``.

    Raises:
        ValueError: ``workers`` or ``n_frames`` < 1.
        RuntimeError: a dataset run failed.
    """
    workers = workers or os.cpu_count() or 1
    if workers < 1 or n_frames < 1:
        raise ValueError(f"workers and n_frames must be >= 1, got {workers} and {n_frames}")
    runs: dict[str, dict[str, float]] = {}
    digests = []
    with tempfile.TemporaryDirectory(prefix="auvsim_bench_dataset_") as tmp:
        for key, w in (("one_worker", 1), ("n_workers", workers)):
            out_dir = Path(tmp) / key
            wall, cpu = _timed([sys.executable, "-m", "sim.cli", "dataset", "--n", str(n_frames), "--seed", str(seed),
                                "--workers", str(w), "--out", str(out_dir), "--no-progress"])
            runs[key] = {"workers": w, "wall_s": round(wall, 3), "cpu_s": round(cpu, 3),
                         "frames_per_s": round(n_frames / wall, 2), "cpu_frames_per_s": round(n_frames / cpu, 2)}
            digests.append(_images_digest(out_dir))
    wall, cpu = _timed([sys.executable, "-c", WORKER_IMPORTS])
    return {
        "n_frames": n_frames,
        "workers": workers,
        "seed": seed,
        **runs,
        "workers_speedup": round(runs["one_worker"]["wall_s"] / runs["n_workers"]["wall_s"], 3),
        "cpu_per_frame_ratio": round(runs["n_workers"]["cpu_s"] / runs["one_worker"]["cpu_s"], 3),
        "startup": {"wall_s": round(wall, 3), "cpu_s": round(cpu, 3)},
        "identical_across_workers": digests[0] == digests[1],
    }
