"""Pinned FLS reference frames: labels exact, images within a stated tolerance on any machine.

The bytes of a rendered frame's floating-point parts depend on the machine: numpy picks its
SIMD loops by CPU (with AVX-512 its float64 ``power``, ``sin``, ``arctan2`` ... come from SVML,
1 ulp apart from the AVX2 loops), OpenBLAS picks its matrix kernels by CPU (SkylakeX kernels
on an AVX-512 machine, Haswell/Zen kernels on an AVX2 one: another summation order in the ray
rotations), OpenCV picks its own SIMD paths, and a fresh install may bring other versions of
all of them. Measured on one AMD Zen 4 by forcing the other kernels
(``NPY_DISABLE_CPU_FEATURES``, ``OPENBLAS_CORETYPE``, ``OPENCV_CPU_DISABLE``,
``NUMBA_CPU_NAME``; README "Determinism"): the label masks, box labels, visibility, ray
counts and noise generator state never changed; ray directions and distances moved by at most
a few ulp (1e-13 m), object centroid range / azimuth / elevation by 1-2 ulp, the noise-free
mean intensity only at values 80 dB below the noise floor, and with OpenCV's SSE-only loops
the realised intensities by one float32 ulp (relative 3.5e-7) and at most 7 of 791,312 polar
pixels by one grey level. numba's target CPU changed nothing (no fast-math in its kernels).

So a pinned reference holds, per frame:

- labels, compared exactly (:func:`frame_labels`): the SHA-256 of the polar and fan label
  masks, each object's id, names, class, flags, ray count, visible fraction and polar box, the
  capture time, the image shapes and the noise generator's state after the frame; geometric
  floats (the object centroid's range, azimuth and elevation and the fan box, which come from
  trigonometry and matrix products, and the sonar pose) within :data:`GEOMETRY_REL_TOL` /
  :data:`GEOMETRY_ABS_TOL`;
- image summaries (:func:`frame_images`): the 256-bin histograms and the sums over
  :data:`U8_BLOCK_PX` square blocks of the 8-bit polar and fan images, and the mean level in
  dB re the noise floor (clipped :data:`DB_FLOOR` below it) over :data:`DB_BLOCK_PX` blocks of
  the mean and realised intensities. A grey-level step of one pixel moves one block sum by one
  and one histogram count between bins, so the 8-bit images may differ by at most
  :data:`U8_STEP_FRACTION` of their pixel count in grey-level steps (summed absolute block-sum
  differences) and in pixels moved between histogram bins; the dB block means by
  :data:`DB_BLOCK_ATOL`.

A 1 % gain change gives 0.03-0.16 grey-level steps a pixel (a 0.1 % one 0.003-0.016), 30 to
1,600 times the budget; the tests show it fails. Same machine and versions, every byte is the
same: :attr:`CaseRenders.digest` is the SHA-256 of all of them
(:func:`sim.sensors.fls_digest.update_with_render`), and the reference keeps the digests of the
machine that pinned it with its :func:`numerics_fingerprint`.
"""

from __future__ import annotations

import hashlib
import json
import math
import platform
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from sim.sensors.fls_digest import update_with_render
from sim.rng import component_rng

CASES = ("bench", "train/0", "train/1", "wide/1", "wide/3")
"""The pinned renders: ``bench`` is ``auvsim bench fls``'s pose sequence (warm-up + 2 frames);
``NAME/I`` the first two frames of dataset scene ``I`` of randomization ``NAME`` (seed 0)."""

U8_BLOCK_PX = 16  # 16 x 16 blocks: a block sum of 8-bit pixels fits a uint16
U8_STEP_FRACTION = 1e-4  # grey-level steps allowed per pixel of an 8-bit image (measured <= 1.2e-5)
DB_BLOCK_PX = 32
DB_FLOOR = -60.0  # dB re the noise power: lower levels (far below the noise) count as this
DB_BLOCK_ATOL = 1e-4  # dB, block means of the mean and realised intensity (measured <= 2e-6 dB a pixel)
GEOMETRY_REL_TOL = 1e-9  # object centroid range / angles, fan boxes, sonar pose (measured <= 2 ulp)
GEOMETRY_ABS_TOL = 1e-12
IMAGES_FILE = "images.npz"
LABELS_FILE = "labels.json"


@dataclass
class CaseRenders:
    """What :func:`render_case` captured: per-frame labels and image summaries, and the
    SHA-256 of every byte of every render (:func:`sim.sensors.fls_digest.update_with_render`)."""

    labels: list[dict] = field(default_factory=list)
    images: list[dict[str, NDArray]] = field(default_factory=list)
    digest: str = ""


@contextmanager
def capture(renders: CaseRenders) -> Iterator[CaseRenders]:
    """Hook :meth:`sim.sensors.fls.FlsSensor.render` while inside: each render's labels and
    image summaries go to ``renders`` and its bytes into its digest (set on exit)."""
    from sim.sensors.fls import FlsSensor

    h = hashlib.sha256()
    inner = FlsSensor.render

    def hooked(self, *args, **kwargs):
        out = inner(self, *args, **kwargs)
        update_with_render(h, out, self.rng)
        renders.labels.append(frame_labels(out, self.rng))
        renders.images.append(frame_images(out, self.echo.noise_power))
        return out

    FlsSensor.render = hooked
    try:
        yield renders
    finally:
        FlsSensor.render = inner
        renders.digest = h.hexdigest()


def render_case(case: str, perturb: Callable[[], object] | None = None) -> CaseRenders:
    """Render one of :data:`CASES` and capture it (``perturb``: called first, e.g. by a test
    that patches the renderer to show the comparison fails).

    Raises:
        ValueError: ``case`` is not one of :data:`CASES`.
    """
    if case not in CASES:
        raise ValueError(f"unknown FLS reference case {case!r}; the cases are {', '.join(CASES)}")
    from scenarios.load import load_scenario
    from sim.bench import fls as bench_fls
    from sim.dataset.generate import RANDOMIZATION_PRESETS, RenderSettings, fls_config, scene_spec
    from sim.dataset.scene_render import render_frames

    if perturb is not None:
        perturb()
    with capture(CaseRenders()) as out:
        if case == "bench":
            bench_fls.run(load_scenario("cssn_lawnmower"), 2, without_truth=False, baseline=False)
        else:
            name, index = case.split("/")
            spec = scene_spec(0, int(index), RANDOMIZATION_PRESETS[name])
            render_frames(spec, fls_config(spec, RenderSettings()), component_rng(0, f"dataset/fls/{index}"), 2)
    return out


def _sha(a) -> str:
    a = np.ascontiguousarray(a)
    return hashlib.sha256(f"{a.dtype}{a.shape}".encode() + a.tobytes()).hexdigest()


def _floats(a) -> list:
    return [float(v) for v in np.asarray(a, dtype=float).ravel()]


def frame_labels(render, rng: np.random.Generator) -> dict:
    """The labels of one :class:`sim.sensors.fls.FlsRender` as JSON-ready values: ``exact``
    (compared for equality) and ``geometry`` (floats compared within :data:`GEOMETRY_REL_TOL`);
    ``rng``: the sensor's noise generator after the frame."""
    f, t = render.frame, render.truth
    objects, geometry = [], []
    for o in t.objects:
        objects.append({
            "id": int(o.id), "name": o.name, "class_name": o.class_name, "is_target": bool(o.is_target),
            "visible": bool(o.visible), "visible_fraction": None if math.isnan(o.visible_fraction)
            else float(o.visible_fraction), "n_rays_hit": int(o.n_rays_hit), "in_fov": bool(o.in_fov),
            "bbox_polar": None if o.bbox_polar is None else [int(v) for v in o.bbox_polar],
            "pos_ned": _floats(o.pos_ned)})
        geometry.append({"range_m": float(o.range_m), "azimuth_rad": float(o.azimuth_rad),
                         "elevation_rad": float(o.elevation_rad),
                         "bbox_xyxy": None if o.bbox_xyxy is None else _floats(o.bbox_xyxy)})
    exact = {"t_s": [float(f.t_s), float(t.t_s)], "polar_shape": list(f.polar.shape), "fan_shape": list(f.fan.shape),
             "mask_polar_sha256": _sha(t.mask_polar), "mask_fan_sha256": _sha(t.mask_fan),
             "rng_state": repr(rng.bit_generator.state), "objects": objects}
    return {"exact": exact, "geometry": {"objects": geometry, "pos_ned": _floats(t.pos_ned), "R_ns": _floats(t.R_ns)}}


def _block_sums(a: NDArray, block: int) -> NDArray[np.int64] | NDArray[np.float64]:
    """Sums of ``a`` (2-D) over ``block`` x ``block`` tiles (the last row and column of tiles
    may be smaller)."""
    a = np.asarray(a, dtype=np.int64 if a.dtype.kind in "ui" else np.float64)
    rows = np.add.reduceat(a, np.arange(0, a.shape[0], block), axis=0)
    return np.add.reduceat(rows, np.arange(0, a.shape[1], block), axis=1)


def _db_block_means(x: NDArray[np.float32], noise_power: float) -> NDArray[np.float32]:
    db = 10.0 * np.log10(np.maximum(np.asarray(x, dtype=np.float64) / noise_power, 10.0 ** (0.1 * DB_FLOOR)))
    return (_block_sums(db, DB_BLOCK_PX) / _block_sums(np.ones(db.shape), DB_BLOCK_PX)).astype(np.float32)


def u8_summary(name: str, img: NDArray[np.uint8]) -> dict[str, NDArray]:
    """``{name}_hist`` (256 counts) and ``{name}_blocks`` (sums over :data:`U8_BLOCK_PX`
    blocks) of an 8-bit image."""
    return {f"{name}_hist": np.bincount(np.asarray(img).ravel(), minlength=256).astype(np.uint32),
            f"{name}_blocks": _block_sums(img, U8_BLOCK_PX).astype(np.uint16)}


def frame_images(render, noise_power: float) -> dict[str, NDArray]:
    """The image summaries of one render (see the module docstring); ``noise_power``: the
    receiver noise power the dB levels refer to (linear, as the intensities)."""
    f = render.frame
    out = {**u8_summary("polar", f.polar), **u8_summary("fan", f.fan)}
    out["mean_db_blocks"] = _db_block_means(render.mean_intensity, noise_power)
    out["intensity_db_blocks"] = _db_block_means(render.intensity, noise_power)
    return out


def _close(a, b) -> bool:
    if a is None or b is None:
        return a is b
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return a.shape == b.shape and bool(np.all(np.abs(a - b) <= GEOMETRY_ABS_TOL + GEOMETRY_REL_TOL * np.abs(b)))


def compare_labels(ref: dict, got: dict) -> list[str]:
    """Differences of one frame's labels (:func:`frame_labels`) from the reference ``ref``: any
    exact field not equal, any geometric float outside the tolerance; empty when they agree."""
    bad = []
    re, ge = ref["exact"], got["exact"]
    for key in re:
        if key == "objects":
            continue
        if re[key] != ge.get(key):
            bad.append(f"{key} differs")
    if len(re["objects"]) != len(ge["objects"]):
        return bad + [f"{len(ge['objects'])} objects, reference {len(re['objects'])}"]
    for ro, go in zip(re["objects"], ge["objects"]):
        bad += [f"object {ro['id']} {k}: {go.get(k)!r}, reference {v!r}" for k, v in ro.items() if go.get(k) != v]
    rg, gg = ref["geometry"], got["geometry"]
    for key in ("pos_ned", "R_ns"):
        if not _close(gg[key], rg[key]):
            bad.append(f"sonar {key} differs beyond {GEOMETRY_REL_TOL:g} relative")
    for ro, rgo, ggo in zip(re["objects"], rg["objects"], gg["objects"]):
        bad += [f"object {ro['id']} {k}: {ggo[k]!r}, reference {v!r} (tolerance {GEOMETRY_REL_TOL:g} relative)"
                for k, v in rgo.items() if not _close(ggo[k], v)]
    return bad


def image_differences(ref: dict[str, NDArray], got: dict[str, NDArray]) -> dict[str, float]:
    """Measured differences of one frame's image summaries (those in ``got``) from the
    reference: per 8-bit image the grey-level steps (summed absolute block-sum differences) and
    the pixels moved between histogram bins, each as a fraction of its pixel count; the largest
    dB block-mean difference of the mean and realised intensities. Different shapes give ``inf``."""
    out: dict[str, float] = {}
    for name in ("polar", "fan"):
        if f"{name}_hist" not in got:
            continue
        rb, gb, rh, gh = ref[f"{name}_blocks"], got[f"{name}_blocks"], ref[f"{name}_hist"], got[f"{name}_hist"]
        n_px = float(rh.sum())
        if rb.shape != gb.shape or gh.sum() != n_px:
            out[f"{name}_steps"] = out[f"{name}_moved"] = math.inf
            continue
        out[f"{name}_steps"] = float(np.abs(rb.astype(np.int64) - gb).sum()) / n_px
        out[f"{name}_moved"] = 0.5 * float(np.abs(rh.astype(np.int64) - gh).sum()) / n_px
    for name in ("mean_db_blocks", "intensity_db_blocks"):
        if name not in got:
            continue
        r, g = ref[name], got[name]
        out[name] = math.inf if r.shape != g.shape else float(np.abs(r.astype(np.float64) - g).max())
    return out


def compare_images(ref: dict[str, NDArray], got: dict[str, NDArray]) -> list[str]:
    """The differences (:func:`image_differences`) beyond :data:`U8_STEP_FRACTION` and
    :data:`DB_BLOCK_ATOL`, one line each; empty when within the tolerance."""
    bad = []
    for key, value in image_differences(ref, got).items():
        limit = DB_BLOCK_ATOL if key.endswith("db_blocks") else U8_STEP_FRACTION
        unit = "dB" if key.endswith("db_blocks") else "of the pixels"
        if not value <= limit:
            bad.append(f"{key} {value:.3g} {unit}, allowed {limit:g}")
    return bad


def compare_case(ref: CaseRenders, got: CaseRenders) -> list[str]:
    """Every difference of ``got`` from the reference ``ref`` beyond the tolerance, each line
    prefixed with its frame; empty when they agree."""
    if len(ref.labels) != len(got.labels):
        return [f"{len(got.labels)} renders, reference {len(ref.labels)}"]
    bad = []
    for i, (rl, gl, ri, gi) in enumerate(zip(ref.labels, got.labels, ref.images, got.images)):
        bad += [f"frame {i}: {line}" for line in compare_labels(rl, gl) + compare_images(ri, gi)]
    return bad


def numerics_fingerprint() -> dict:
    """What decides the bytes of a render on this machine: the versions of Python, numpy,
    numba, llvmlite, MuJoCo and OpenCV, the architecture, numpy's enabled CPU features,
    OpenCV's dispatched ones, numba's target CPU, and a hash of matrix products and
    transcendental functions of fixed inputs (OpenBLAS has no feature list to read: this is
    how its kernel choice shows)."""
    import cv2
    import llvmlite
    import llvmlite.binding as llvm
    import mujoco
    import numba

    try:
        from numpy._core._multiarray_umath import __cpu_features__
    except ImportError:  # numpy 1.x
        from numpy.core._multiarray_umath import __cpu_features__

    rng = np.random.default_rng(20261201)
    a = rng.standard_normal((4099, 3))
    q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    x = rng.uniform(-3.0, 3.0, 4099)
    h = hashlib.sha256()
    for out in (a @ q.T, q.T @ a[0], q @ q, np.einsum("ij,ij->i", a, a), np.power(np.abs(x), 1.7), np.sin(x),
                np.cos(x), np.arctan2(x, x[::-1]), np.arcsin(x / 3.0), np.exp(x), np.log10(np.abs(x) + 1e-3)):
        h.update(np.ascontiguousarray(out).tobytes())
    return {"python": platform.python_version(), "machine": platform.machine(), "numpy": np.__version__,
            "numba": numba.__version__, "llvmlite": llvmlite.__version__, "mujoco": mujoco.__version__,
            "opencv": cv2.__version__, "numpy_cpu_features": sorted(k for k, v in __cpu_features__.items() if v),
            "opencv_cpu_features": cv2.getCPUFeaturesLine(),
            "numba_cpu": [numba.config.CPU_NAME or llvm.get_host_cpu_name(), numba.config.CPU_FEATURES or ""],
            "blas_and_ufunc_probe": h.hexdigest()}


def write_reference(directory: Path, cases: dict[str, CaseRenders]) -> None:
    """Write ``cases`` as a reference: ``labels.json`` (labels, digests, the fingerprint of this
    machine) and ``images.npz`` (the image summaries, compressed)."""
    directory.mkdir(parents=True, exist_ok=True)
    labels = {"fingerprint": numerics_fingerprint(),
              "digests": {k: c.digest for k, c in cases.items()},
              "labels": {k: c.labels for k, c in cases.items()}}
    (directory / LABELS_FILE).write_text(json.dumps(labels, indent=1) + "\n")
    arrays = {f"{k}/{i}/{name}": a for k, c in cases.items() for i, frame in enumerate(c.images)
              for name, a in frame.items()}
    np.savez_compressed(directory / IMAGES_FILE, **arrays)


@dataclass(frozen=True)
class Reference:
    """A pinned reference (:func:`load_reference`): ``cases`` by name, the ``digests`` and
    ``fingerprint`` of the machine that wrote it."""

    cases: dict[str, CaseRenders]
    digests: dict[str, str]
    fingerprint: dict


def load_reference(directory: Path) -> Reference:
    """Read what :func:`write_reference` wrote into ``directory``.

    Raises:
        FileNotFoundError: a file is missing.
    """
    doc = json.loads((directory / LABELS_FILE).read_text())
    with np.load(directory / IMAGES_FILE) as z:
        arrays = {k: z[k] for k in z.files}
    cases = {}
    for name, labels in doc["labels"].items():
        images = [{k.rsplit("/", 1)[1]: a for k, a in arrays.items() if k.startswith(f"{name}/{i}/")}
                  for i in range(len(labels))]
        cases[name] = CaseRenders(labels=labels, images=images, digest=doc["digests"][name])
    return Reference(cases=cases, digests=doc["digests"], fingerprint=doc["fingerprint"])
