"""The realism report: real forward-looking sonar frames against a matched simulated set.

:func:`realism_report` reads the real frames from a folder, fits their fan
(:func:`sim.dataset.real_frames.fit_fan_outline`), draws matched water-tank scenes with a fixed
seed (:mod:`sim.dataset.tank_scenes`), matches the display gain on the mid-range background,
renders them onto the real pixel grid, and measures both sets with the same code
(:mod:`sim.realism.image_measures`): the statistics table, the range profile and the classifier
two-sample tests on background and object patches (:mod:`sim.realism.two_sample`). It can do
so for several image-formation models in one run (:data:`FORMATIONS`: ``before``, the
sonar's formation without the realism work, and ``after``, the formation estimated for the
ARIS 3000 in the tank, and ``shells``, that estimate with objects as thin shells), so they
are compared on the same scenes, seed and real frames.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from sim.realism.image_measures import MEASURES, FrameSetMeasures
from sim.dataset.real_frames import RealFrames, fan_groups, fit_fan_outline, load_real_frames
from sim.dataset.tank_scenes import (TANK, TANK_FORMATION, TANK_FORMATION_SHELLS, TankGeometry, draw_scenes,
                                     render_tank_frames)
from sim.realism.gain_match import background_grey, calibrate_gain_db
from sim.realism.two_sample import (TwoSampleResult, balanced_sets, cnn_judge, feature_judges,
                                    patch_features)

#: Image-formation models the report can render, by name: FLS config overrides over the
#: ``aris3000`` preset (the display gain is matched afterwards, for each model alike).
FORMATIONS: dict[str, dict] = {
    "before": {},
    "after": TANK_FORMATION,
    "shells": TANK_FORMATION_SHELLS,
}
#: Goals of the report: two-sample accuracies at most these (background, object patches);
#: statistics within 20 % of the real value; the range profile's correlation at least 0.8.
GOAL_ACCURACY = {"background": 0.75, "object": 0.80}
GOAL_RELATIVE = 0.20
GOAL_PROFILE_CORR = 0.80
N_BEAMS = 128  # the ARIS 3000's beams across the fan
#: Fewer patches than this per set and kind: the accuracies are reported, not judged.
MIN_JUDGED_PATCHES = 200
#: Fewer real frames of one fan than this: the report warns that the fan fit is unreliable.
MIN_FIT_FRAMES = 50
PRESET = "aris3000"


@dataclass
class SetResult:
    """One set's measures: the :data:`MEASURES` values, the range profile, and the patches."""

    name: str
    frames: int
    measures: dict[str, float]
    profile: NDArray[np.float64]
    bg_patches: list
    obj_patches: list
    bg_groups: NDArray[np.int64]
    obj_groups: NDArray[np.int64]
    examples: list = field(default_factory=list)  # a few (image) for the figure
    gain_db: float | None = None


@dataclass
class FormationResult:
    """The simulated set of one formation model against the real set."""

    name: str
    sim: SetResult
    profile_corr: float
    judges: dict[str, list[TwoSampleResult]]


@dataclass
class RealismReport:
    """Everything :func:`realism_report` measured (``to_json`` for a file)."""

    real_dir: str
    seed: int
    outline: dict
    real: SetResult
    formations: list[FormationResult]
    notes: list[str] = field(default_factory=list)
    options: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        """The report as JSON-ready data (NaN, where nothing was measured, as None)."""
        return _finite_or_none(self._json())

    def _json(self) -> dict:
        def judges(d):
            return {k: [{"judge": j.judge, "accuracy": j.accuracy, "n_scored": j.n_scored, "ci95": list(j.ci95)}
                        for j in v] for k, v in d.items()}
        return {
            "real_dir": self.real_dir, "seed": self.seed, "fan_outline": self.outline,
            "real": {"frames": self.real.frames, "measures": self.real.measures,
                     "range_profile": self.real.profile.tolist()},
            "simulated": {f.name: {"frames": f.sim.frames, "gain_db": f.sim.gain_db, "measures": f.sim.measures,
                                   "range_profile": f.sim.profile.tolist(), "profile_corr": f.profile_corr,
                                   "two_sample": judges(f.judges),
                                   "within_20pct": within_goal(self.real.measures, f.sim.measures)}
                          for f in self.formations},
            "goals": {"accuracy_at_most": GOAL_ACCURACY, "relative_error_at_most": GOAL_RELATIVE,
                      "profile_corr_at_least": GOAL_PROFILE_CORR, "min_judged_patches": MIN_JUDGED_PATCHES},
            "measure_labels": {m.key: {"label": m.label, "unit": m.unit} for m in MEASURES},
            "notes": list(self.notes),
            "options": dict(self.options),
        }


def _finite_or_none(x):
    if isinstance(x, dict):
        return {k: _finite_or_none(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite_or_none(v) for v in x]
    if isinstance(x, (float, np.floating)):
        return float(x) if np.isfinite(x) else None
    return x


def _check_args(real_dir, n_sim, seed, near_m, formations, limit_real) -> tuple[str, ...]:
    """The formations as a tuple of known names; ValueError naming the first bad argument."""
    import os

    if not isinstance(real_dir, (str, os.PathLike)):
        raise ValueError(f"real_dir must be a folder path (str or Path), got {real_dir!r}")
    for name, value, lo in (("n_sim", n_sim, 1), ("seed", seed, 0)):
        if not isinstance(value, (int, np.integer)) or isinstance(value, bool) or value < lo:
            raise ValueError(f"{name} must be a whole number >= {lo}, got {value!r}")
    if limit_real is not None and (not isinstance(limit_real, (int, np.integer)) or isinstance(limit_real, bool)
                                   or limit_real < 1):
        raise ValueError(f"limit_real must be None or a whole number >= 1, got {limit_real!r}")
    if isinstance(near_m, bool) or not isinstance(near_m, (int, float, np.floating, np.integer)) or not (
            np.isfinite(near_m) and near_m > 0):
        raise ValueError(f"near_m must be a finite number > 0 (m), got {near_m!r}")
    if isinstance(formations, str) or not all(isinstance(f, str) for f in formations):
        raise ValueError(f"formations must be a sequence of names from {sorted(FORMATIONS)}, got {formations!r}")
    bad = [f for f in formations if f not in FORMATIONS]
    if bad or not formations:
        raise ValueError(f"formations: unknown {bad or formations!r}; allowed: {sorted(FORMATIONS)}")
    return tuple(formations)


def near_range_limits_m(near_far_ratio: float) -> tuple[float, float]:
    """The near ranges (m) the ``aris3000`` preset can render for a fan of this near/far
    ratio: its minimum range up to the one whose far range is its maximum."""
    from scenarios.fls_presets import PRESETS

    p = PRESETS[PRESET]
    return float(p.range_min_m), float(p.range_max_m * near_far_ratio)


def within_goal(real: dict[str, float], sim: dict[str, float]) -> dict[str, bool | None]:
    """Per measure: whether the simulated value is within :data:`GOAL_RELATIVE` of the real
    one with the same sign (None where either is not finite)."""
    out: dict[str, bool | None] = {}
    for m in MEASURES:
        a, b = real.get(m.key, np.nan), sim.get(m.key, np.nan)
        if not (np.isfinite(a) and np.isfinite(b)):
            out[m.key] = None
        else:
            out[m.key] = bool(np.sign(a) == np.sign(b) and abs(b - a) <= GOAL_RELATIVE * abs(a))
    return out


def _measure_set(name: str, pairs, geom, n_beams: int, rng: np.random.Generator, n_examples: int = 4,
                 progress: Callable[[int], None] | None = None) -> SetResult:
    acc = FrameSetMeasures(geom, n_beams)
    bg_g, obj_g, examples = [], [], []
    n = 0
    for k, (image, mask) in enumerate(pairs):
        nb, no = len(acc.bg_patches), len(acc.obj_patches)
        acc.add(image, mask, rng)
        bg_g += [k] * (len(acc.bg_patches) - nb)
        obj_g += [k] * (len(acc.obj_patches) - no)
        if len(examples) < n_examples:
            examples.append(image)
        n += 1
        if progress is not None:
            progress(1)
    return SetResult(name, n, acc.summary(), acc.range_profile(), acc.bg_patches, acc.obj_patches,
                     np.array(bg_g, dtype=np.int64), np.array(obj_g, dtype=np.int64), examples)


def _judge(real: SetResult, sim: SetResult, seed: int, cnn: bool) -> dict[str, list[TwoSampleResult]]:
    out = {}
    for kind, attr in (("background", "bg"), ("object", "obj")):
        rp, sp = getattr(real, f"{attr}_patches"), getattr(sim, f"{attr}_patches")
        if len(rp) < 10 or len(sp) < 10:
            out[kind] = []
            continue
        rf = np.array([patch_features(p) for p in rp])
        sf = np.array([patch_features(p) for p in sp])
        rng = np.random.default_rng(seed)
        X, y, g = balanced_sets(rf, getattr(real, f"{attr}_groups"), sf, getattr(sim, f"{attr}_groups"), rng)
        res = feature_judges(X, y, g, seed=seed)
        if cnn:
            P, yp, gp = balanced_sets(np.stack(rp), getattr(real, f"{attr}_groups"), np.stack(sp),
                                      getattr(sim, f"{attr}_groups"), np.random.default_rng(seed))
            res.append(cnn_judge(P, yp, gp, seed=seed))
        out[kind] = res
    return out


def realism_report(real_dir: str, *, n_sim: int = 200, seed: int = 0, near_m: float = 0.7,
                   formations: tuple[str, ...] = ("before", "after"), cnn: bool = False,
                   limit_real: int | None = None, tank: TankGeometry = TANK,
                   progress: Callable[[str, int], Callable[[int], None]] | None = None) -> RealismReport:
    """Measure the real frames of ``real_dir`` against ``n_sim`` simulated ones per formation.

    Args:
        real_dir: folder of real frames (:func:`sim.dataset.real_frames.load_real_frames`).
        n_sim: simulated frames per formation (one per drawn scene).
        seed: root seed of the scenes, the noise and the patch draws.
        near_m: the real window's near range, m (sets the metric scale).
        formations: names in :data:`FORMATIONS`.
        cnn: add the small-CNN judge (needs torch).
        limit_real: read at most this many real frames.
        progress: ``progress(label, total)`` returns a per-item callback (a progress bar).

    The real frames are sorted by fan outline (:func:`sim.dataset.real_frames.fan_groups`):
    the largest group is measured and matched, the others (recorded with another window or
    exported at another aspect) are left out and named in ``notes``.

    Raises:
        sim.dataset.real_frames.RealDataError: the folder cannot be read, or its frames hold
            no sonar fan.
        ValueError: a bad argument (named in the message), or a ``near_m`` outside
            :func:`near_range_limits_m` for the fitted fan.
    """
    formations = _check_args(real_dir, n_sim, seed, near_m, formations, limit_real)
    loaded: RealFrames = load_real_frames(real_dir, limit=limit_real)
    groups = fan_groups(loaded.images)
    used = groups[0]
    outline = fit_fan_outline(loaded.images[used])
    lo, hi = near_range_limits_m(outline.near_far_ratio)
    if not lo <= near_m <= hi:
        raise ValueError(f"near_m {near_m:g} m: the {PRESET} preset renders ranges {lo:g}-"
                         f"{hi / outline.near_far_ratio:g} m, so with this fan's near/far ratio "
                         f"{outline.near_far_ratio:.3f} the near range must lie in [{lo:g}, {hi:.3f}] m")
    notes = []
    if len(groups) > 1:
        notes.append(f"fan outlines: {len(groups)} groups of {', '.join(str(len(g)) for g in groups)} frames; "
                     f"the largest ({len(used)} frames) is measured, the others are left out")
    if len(used) < MIN_FIT_FRAMES:
        notes.append(f"the fan is fitted on {len(used)} frames (fewer than {MIN_FIT_FRAMES}): its outline, and so "
                     "the matched geometry, may be off")
    images = loaded.images[used]
    if loaded.masks is None:
        notes.append("no masks/ in the folder: the object measures and object patches are left out")
    masks = loaded.masks[used] if loaded.masks is not None else np.zeros_like(images)
    geom = outline.geometry(near_m)
    bar = progress("real frames", len(images)) if progress else None
    real_set = _measure_set("real", zip(images, masks), geom, N_BEAMS, np.random.default_rng(seed), progress=bar)
    target_grey = background_grey(list(zip(images, masks)), geom)
    scenes = draw_scenes(n_sim, seed, tank)
    results = []
    for name in formations:
        over = dict(FORMATIONS[name])
        over["gain_db"] = calibrate_gain_db(target_grey, scenes[:8], geom, seed=seed + 1, fls_overrides=over,
                                            tank=tank)
        bar = progress(f"simulated frames ({name})", n_sim) if progress else None
        frames = ((f.image, f.mask) for f in render_tank_frames(scenes, geom, seed=seed, fls_overrides=over,
                                                                 tank=tank))
        sim_set = _measure_set(name, frames, geom, N_BEAMS, np.random.default_rng(seed), progress=bar)
        sim_set.gain_db = over["gain_db"]
        corr = float(np.corrcoef(real_set.profile, sim_set.profile)[0, 1])
        results.append(FormationResult(name, sim_set, corr, _judge(real_set, sim_set, seed, cnn)))
    od = {k: getattr(outline, k) for k in ("width_px", "height_px", "apex_x_px", "apex_y_px", "near_px", "far_px",
                                           "half_angle_rad", "edge_rms_px")}
    od.update(near_m=geom.range_min_m, far_m=geom.range_max_m, m_per_px=geom.m_per_px,
              fan_groups=[len(g) for g in groups], frames_read=int(len(loaded.images)))
    small = [f"{f.name} {kind}" for f in results for kind, res in f.judges.items()
             if res and res[0].n_scored < MIN_JUDGED_PATCHES]
    if small:
        notes.append(f"fewer than {MIN_JUDGED_PATCHES} patches ({', '.join(small)}): those accuracies are "
                     "not judged against the goal (more frames: --frames, and more real frames)")
    options = {"n_sim": int(n_sim), "seed": int(seed), "near_m": float(near_m), "formations": list(formations),
               "cnn": bool(cnn), "limit_real": limit_real, "formation_settings": {f: FORMATIONS[f] for f in formations},
               "tank": {k: getattr(tank, k) for k in tank.__dataclass_fields__}}
    return RealismReport(str(real_dir), int(seed), od, real_set, results, notes, options)


def report_lines(rep: RealismReport) -> list[str]:
    """The report as console lines: the fan fit, the table (real, then each formation, a
    ``*`` where within the goal), the range profiles and the two-sample accuracies."""
    o = rep.outline
    read = o.get("frames_read", rep.real.frames)
    used = f"{rep.real.frames} frames" if read == rep.real.frames else f"{rep.real.frames} of {read} frames"
    lines = [f"real frames: {rep.real_dir} ({used}); fan apex ({o['apex_x_px']:.1f}, "
             f"{o['apex_y_px']:.1f}) px, near/far {o['near_px']:.1f}/{o['far_px']:.1f} px, half-angle "
             f"{np.degrees(o['half_angle_rad']):.2f} deg, fit rms {o['edge_rms_px']:.2f} px; window "
             f"{o['near_m']:.2f}-{o['far_m']:.2f} m at {1000 * o['m_per_px']:.2f} mm/px",
             ""]
    names = [f.name for f in rep.formations]
    head = f"{'measure':62s} {'real':>8s}" + "".join(f" {n:>9s}" for n in names)
    lines += [head, "-" * len(head)]
    goals = {f.name: within_goal(rep.real.measures, f.sim.measures) for f in rep.formations}
    for m in MEASURES:
        label = f"{m.label}{f' ({m.unit})' if m.unit else ''}"
        row = f"{label[:62]:62s} {rep.real.measures[m.key]:8.3f}"
        for f in rep.formations:
            ok = goals[f.name][m.key]
            row += f" {f.sim.measures[m.key]:8.3f}{'*' if ok else ' '}"
        lines.append(row)
    lines.append("")
    lines.append(f"{'mean grey against range, near to far':40s} real " + " ".join(f"{v:.2f}" for v in rep.real.profile))
    for f in rep.formations:
        lines.append(f"{'':40s} {f.name:>4s} " + " ".join(f"{v:.2f}" for v in f.sim.profile)
                     + f"  (correlation {f.profile_corr:+.2f}{'*' if f.profile_corr >= GOAL_PROFILE_CORR else ''})")
    lines.append("")
    lines.append("two-sample classifier, held-out accuracy (0.5: indistinguishable; goal: background <= 0.75, "
                 f"object <= 0.80; judged from {MIN_JUDGED_PATCHES} patches)")
    for f in rep.formations:
        for kind, res in f.judges.items():
            judged = bool(res) and res[0].n_scored >= MIN_JUDGED_PATCHES
            txt = ", ".join(f"{j.judge} {j.accuracy:.3f} [{j.ci95[0]:.2f}, {j.ci95[1]:.2f}]"
                            f"{'*' if judged and j.accuracy <= GOAL_ACCURACY[kind] else ''}" for j in res)
            lines.append(f"  {f.name:>6s} {kind:10s} ({res[0].n_scored if res else 0} patches): "
                         f"{txt or 'too few patches'}{'' if judged or not res else ' (too few to judge)'}")
    lines.append(f"(* within the goal: a statistic within {GOAL_RELATIVE:.0%} of the real value with its sign, the "
                 f"range profile's correlation >= {GOAL_PROFILE_CORR}, an accuracy at most its goal; "
                 "docs/studies/realism.md says what each measures)")
    lines.append("(gain matched on the mid-range background: "
                 + ", ".join(f"{f.name} {f.sim.gain_db:+.1f} dB" for f in rep.formations) + ")")
    for note in rep.notes:
        lines.append(f"note: {note}")
    return lines


def side_by_side_png(rep: RealismReport, path, *, include_real: bool = True) -> None:
    """A figure: a row of real frames (unless ``include_real`` is False: a figure that may be
    published without the real set's images), a row per formation's simulated frames (the
    same scenes for every formation), and the range profiles; written as a PNG."""
    import cv2

    rows = ([("real", rep.real.examples)] if include_real else []) + [
        (f"simulated: {f.name}", f.sim.examples) for f in rep.formations]
    n = max(len(ex) for _, ex in rows)
    h, w = rep.formations[0].sim.examples[0].shape if rep.formations else rep.real.examples[0].shape
    pad = 24
    canvas = np.zeros((len(rows) * (h + pad) + 200, n * w), dtype=np.uint8)
    for i, (label, ex) in enumerate(rows):
        y0 = i * (h + pad)
        cv2.putText(canvas, label, (6, y0 + 17), cv2.FONT_HERSHEY_SIMPLEX, 0.55, 255, 1, cv2.LINE_AA)
        for j, img in enumerate(ex):
            canvas[y0 + pad:y0 + pad + h, j * w:(j + 1) * w] = img
    # range profiles: near (left) to far (right), grey over its mean (1.0 marked), 0 to 2
    y0 = len(rows) * (h + pad)
    x0, pw = 40, canvas.shape[1] - 240
    font = cv2.FONT_HERSHEY_SIMPLEX
    cv2.putText(canvas, "mean grey against range, over its mean", (6, y0 + 18), font, 0.45, 255, 1, cv2.LINE_AA)

    def y_of(v):
        return int(y0 + 190 - np.clip(v, 0, 2) * 80)

    cv2.line(canvas, (x0, y_of(0)), (x0, y_of(2)), 128, 1)  # the axes
    cv2.line(canvas, (x0, y_of(0)), (x0 + pw, y_of(0)), 128, 1)
    for v in (0.0, 1.0, 2.0):
        cv2.putText(canvas, f"{v:.0f}", (x0 - 18, y_of(v) + 4), font, 0.35, 200, 1, cv2.LINE_AA)
        cv2.line(canvas, (x0 - 3, y_of(v)), (x0 + (pw if v == 1.0 else 3), y_of(v)), 90 if v == 1.0 else 128, 1)
    cv2.putText(canvas, "near", (x0, y_of(0) + 0), font, 0.35, 200, 1, cv2.LINE_AA)
    cv2.putText(canvas, "far", (x0 + pw - 20, y_of(0)), font, 0.35, 200, 1, cv2.LINE_AA)
    profiles = [("real", rep.real.profile, 3, 255)] + [(f.name, f.sim.profile, 1, 170 + 40 * (k % 2))
                                                       for k, f in enumerate(rep.formations)]
    for k, (name, prof, thick, shade) in enumerate(profiles):
        xs = x0 + np.linspace(0, pw, len(prof))
        pts = np.stack([xs, [y_of(v) for v in prof]], axis=1).astype(np.int32)
        cv2.polylines(canvas, [pts], False, shade, thick, cv2.LINE_AA)
        ly = y0 + 50 + 22 * k  # legend
        cv2.line(canvas, (x0 + pw + 20, ly), (x0 + pw + 60, ly), shade, thick, cv2.LINE_AA)
        cv2.putText(canvas, name if name == "real" else f"simulated: {name}", (x0 + pw + 66, ly + 4), font, 0.4,
                    255, 1, cv2.LINE_AA)
    cv2.imwrite(str(path), canvas)
