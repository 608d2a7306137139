"""What a sonar image looks like, in numbers: the measures the realism report compares.

Every measure reads fan images (H, W) uint8 with a class-id mask (0 background, 11 the wall,
other ids objects; :data:`sim.dataset.real_frames.MARINE_DEBRIS_CLASSES`) on one
:class:`autonomy.sonar_geometry.FanGeometry`, so real and simulated frames are measured by the
same code on the same pixel grid. Polar measures resample the fan onto (range, azimuth): one
pixel per range step, :data:`AZ_PER_BEAM` samples per beam.

Speckle is the image divided by its local mean (a box of :data:`LOCAL_MEAN_PX` pixels), minus
one; a speckle length is the full width at half maximum of its autocorrelation (linear
interpolation between lags; white noise gives about 1 px). Definitions of every measure are
in :data:`MEASURES` and ``docs/studies/realism.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np
from numpy.typing import NDArray

from autonomy.sonar_geometry import FanGeometry

WALL_ID = 11
AZ_PER_BEAM = 4  # polar azimuth samples per beam
LOCAL_MEAN_PX = 9  # local-mean box (polar samples) behind the speckle
PATCH_PX = 64
N_RANGE_BANDS = 6
ARC_RATIO = 1.15  # a range row (or beam) this much brighter than its neighbours' median is an arc (streak)
SHADOW_RATIO = 0.8


@dataclass(frozen=True)
class Measure:
    """One row of the report: its key, what it says and its unit."""

    key: str
    label: str
    unit: str = ""


MEASURES: tuple[Measure, ...] = (
    Measure("speckle_lag1_range", "speckle correlation between neighbouring range px (lag 1)"),
    Measure("speckle_len_range_mid", "speckle length along range, mid range", "px"),
    Measure("speckle_len_beam_near", "speckle length across beams, near", "beams"),
    Measure("speckle_len_beam_mid", "speckle length across beams, mid", "beams"),
    Measure("speckle_len_beam_far", "speckle length across beams, far", "beams"),
    Measure("bg_skewness", "background patch skewness"),
    Measure("grey_p10", "normalised grey p10 (background patches)"),
    Measure("grey_p90", "normalised grey p90 (background patches)"),
    Measure("low_freq_share", "patch energy share below 1/8 cycle/px (floor texture)"),
    Measure("bright_dim_corr", "row correlation, bright over dim bg patches (per range band)"),
    Measure("arc_rows", "range rows that are thin arcs", "%"),
    Measure("streak_beams", "beams that are radial streaks", "%"),
    Measure("dark_far_near", "dark level (p10 grey) far / near"),
    Measure("object_p99_bg", "object p99 / background median"),
    Measure("object_len_range", "object length along range (median)", "px"),
    Measure("standing_len_range", "standing bottle length along range (median)", "px"),
    Measure("shadow_share", "objects with an acoustic shadow (< 0.8 of background)", "%"),
)


def polar_maps(geom: FanGeometry, n_beams: int, *, margin_px: float = 2.0
               ) -> tuple[NDArray[np.float32], NDArray[np.float32], NDArray[np.float64]]:
    """``cv2.remap`` maps from (range px, azimuth sample) to fan pixels, and the radius of
    each range row (px from the apex). Azimuth: ``n_beams * AZ_PER_BEAM`` samples, one beam
    of margin left off at each edge; range: 1 px steps from the near to the far arc, less
    ``margin_px`` at each end."""
    near_px = geom.range_min_m / geom.m_per_px
    far_px = geom.range_max_m / geom.m_per_px
    r = np.arange(near_px + margin_px, far_px - margin_px, 1.0)[::-1]  # far first, like the fan image
    half = 0.5 * geom.fov_rad * (1.0 - 2.0 / n_beams)
    a = np.linspace(-half, half, (n_beams - 2) * AZ_PER_BEAM)
    x = geom.apex_x_px + r[:, None] * np.sin(a)[None, :]
    y = geom.apex_y_px - r[:, None] * np.cos(a)[None, :]
    return x.astype(np.float32), y.astype(np.float32), r


def fan_radius_px(geom: FanGeometry) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(H, W) radius from the apex (px) and azimuth (rad) of every fan pixel centre."""
    yy, xx = np.mgrid[0:geom.height_px, 0:geom.width_px].astype(np.float64)
    return np.hypot(xx - geom.apex_x_px, geom.apex_y_px - yy), np.arctan2(xx - geom.apex_x_px, geom.apex_y_px - yy)


@dataclass
class FrameSetMeasures:
    """Per-set accumulators; :meth:`add` one frame at a time, :meth:`summary` at the end."""

    geom: FanGeometry
    n_beams: int
    acf_range: list = field(default_factory=list)
    acf_beam: dict = field(default_factory=lambda: {0: [], 1: [], 2: []})
    bg_patches: list = field(default_factory=list)
    bg_patch_band: list = field(default_factory=list)  # range band of each background patch's centre
    obj_patches: list = field(default_factory=list)
    arc_rows: list = field(default_factory=list)
    streak_beams: list = field(default_factory=list)
    band_sum: NDArray | None = None
    band_n: NDArray | None = None
    dark: list = field(default_factory=list)
    objects: list = field(default_factory=list)  # (class id, p99/bg, radial extent px, shadow ratio)

    def __post_init__(self) -> None:
        self._mx, self._my, self._r = polar_maps(self.geom, self.n_beams)
        self._rad, self._az = fan_radius_px(self.geom)
        near_px, far_px = self.geom.range_min_m / self.geom.m_per_px, self.geom.range_max_m / self.geom.m_per_px
        self._fan = (self._rad >= near_px + 1) & (self._rad <= far_px - 1) & (
            np.abs(self._az) <= 0.5 * self.geom.fov_rad - 1.0 / 128)
        self._band = np.clip(((self._rad - near_px) / (far_px - near_px) * N_RANGE_BANDS).astype(int), 0,
                             N_RANGE_BANDS - 1)
        self._patch_ok = cv2.erode(self._fan.astype(np.uint8), np.ones((PATCH_PX, PATCH_PX), np.uint8),
                                   anchor=(0, 0), borderType=cv2.BORDER_CONSTANT, borderValue=0).astype(bool)
        h, w = self._patch_ok.shape
        self._patch_ok[h - PATCH_PX + 1:, :] = False
        self._patch_ok[:, w - PATCH_PX + 1:] = False
        self.band_sum = np.zeros(N_RANGE_BANDS)
        self.band_n = np.zeros(N_RANGE_BANDS)

    # -- one frame ------------------------------------------------------------------------------
    def add(self, image: NDArray[np.uint8], mask: NDArray[np.uint8], rng: np.random.Generator,
            n_bg_patches: int = 4) -> None:
        """Measure one frame: ``image`` (H, W) uint8 and its class-id ``mask`` (H, W)."""
        img = image.astype(np.float32)
        labelled = mask > 0
        near_obj = cv2.dilate(labelled.astype(np.uint8), np.ones((7, 7), np.uint8)).astype(bool)
        bg = self._fan & ~near_obj
        self._speckle(img, bg)
        self._profile(img, bg)
        self._arcs(img)
        self._patches(img, mask, rng, n_bg_patches)
        self._objects(img, mask, bg)

    def _polar(self, img: NDArray[np.float32]) -> NDArray[np.float32]:
        return cv2.remap(img, self._mx, self._my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)

    def _speckle(self, img: NDArray[np.float32], bg: NDArray[np.bool_]) -> None:
        p = self._polar(img)
        valid = cv2.remap(bg.astype(np.uint8), self._mx, self._my, cv2.INTER_NEAREST) > 0
        mean = cv2.blur(p, (LOCAL_MEAN_PX, LOCAL_MEAN_PX))
        ok = valid & (mean > 2.0)
        s = np.where(ok, p / np.maximum(mean, 1e-3) - 1.0, 0.0)
        n_r = s.shape[0]
        mid = slice(n_r // 3, 2 * n_r // 3)
        self.acf_range.append(_acf(s[mid], ok[mid], axis=0, max_lag=8))
        thirds = [slice(2 * n_r // 3, n_r), slice(n_r // 3, 2 * n_r // 3), slice(0, n_r // 3)]  # near, mid, far
        for k, sl in enumerate(thirds):
            self.acf_beam[k].append(_acf(s[sl], ok[sl], axis=1, max_lag=4 * AZ_PER_BEAM))

    def _profile(self, img: NDArray[np.float32], bg: NDArray[np.bool_]) -> None:
        fan = self._fan
        self.band_sum += np.bincount(self._band[fan], weights=img[fan], minlength=N_RANGE_BANDS)
        self.band_n += np.bincount(self._band[fan], minlength=N_RANGE_BANDS)
        near = img[fan & (self._band == 0)]
        far = img[fan & (self._band == N_RANGE_BANDS - 1)]
        if near.size and far.size:
            self.dark.append((float(np.percentile(far, 10)), float(np.percentile(near, 10))))

    def _arcs(self, img: NDArray[np.float32]) -> None:
        p = self._polar(img)
        beams = p.reshape(p.shape[0], -1, AZ_PER_BEAM).mean(axis=2)
        rows = beams.mean(axis=1)
        cols = beams.mean(axis=0)
        self.arc_rows.append(_peaked_share(rows, 11))
        self.streak_beams.append(_peaked_share(cols, 11))

    def _patches(self, img: NDArray[np.float32], mask: NDArray[np.uint8], rng: np.random.Generator,
                 n_bg: int) -> None:
        ys, xs = np.nonzero(self._patch_ok)
        if ys.size == 0:
            return
        labelled = (mask > 0).astype(np.float32)
        got, tries = 0, 0
        while got < n_bg and tries < 20 * n_bg:
            tries += 1
            k = int(rng.integers(ys.size))
            y, x = ys[k], xs[k]
            if labelled[y:y + PATCH_PX, x:x + PATCH_PX].mean() > 0.02:
                continue
            self.bg_patches.append(img[y:y + PATCH_PX, x:x + PATCH_PX].copy())
            self.bg_patch_band.append(int(self._band[y + PATCH_PX // 2, x + PATCH_PX // 2]))
            got += 1
        n_lab, lab, stats, cents = cv2.connectedComponentsWithStats(((mask > 0) & (mask != WALL_ID)).astype(np.uint8))
        h, w = img.shape
        for j in range(1, n_lab):
            if stats[j, cv2.CC_STAT_AREA] < 20:
                continue
            cx, cy = cents[j]
            y0 = int(np.clip(round(cy) - PATCH_PX // 2, 0, h - PATCH_PX))
            x0 = int(np.clip(round(cx) - PATCH_PX // 2, 0, w - PATCH_PX))
            if self._fan[y0:y0 + PATCH_PX, x0:x0 + PATCH_PX].mean() >= 0.95:
                self.obj_patches.append(img[y0:y0 + PATCH_PX, x0:x0 + PATCH_PX].copy())

    def _objects(self, img: NDArray[np.float32], mask: NDArray[np.uint8], bg: NDArray[np.bool_]) -> None:
        if not bg.any():
            return
        bg_med = float(np.median(img[bg]))
        if bg_med <= 0:
            return
        for cid in np.unique(mask):
            if cid == 0 or cid == WALL_ID:
                continue
            n_lab, lab = cv2.connectedComponents((mask == cid).astype(np.uint8))
            for j in range(1, n_lab):
                inst = (lab == j) & self._fan
                if inst.sum() < 20:
                    continue
                vals = img[inst]
                r, a = self._rad[inst], self._az[inst]
                extent = float(r.max() - r.min())
                a_lo, a_hi = np.percentile(a, [20, 80])
                depth = max(extent, 10.0)
                beyond = self._fan & ~(mask > 0) & (self._az >= a_lo) & (self._az <= a_hi) & (
                    self._rad > r.max() + 3) & (self._rad < r.max() + 3 + depth)
                shadow = float(img[beyond].mean() / bg_med) if beyond.sum() >= 20 else np.nan
                self.objects.append((int(cid), float(np.percentile(vals, 99)) / bg_med, extent, shadow))

    # -- the set ----------------------------------------------------------------------------------
    def summary(self) -> dict[str, float]:
        """The :data:`MEASURES` of the frames added so far (NaN where none could be taken)."""
        out: dict[str, float] = {}
        acf_r = _mean_acf(self.acf_range)
        out["speckle_lag1_range"] = float(acf_r[1]) if acf_r is not None else np.nan
        out["speckle_len_range_mid"] = _fwhm(acf_r)
        for k, name in enumerate(("near", "mid", "far")):
            out[f"speckle_len_beam_{name}"] = _fwhm(_mean_acf(self.acf_beam[k])) / AZ_PER_BEAM
        if self.bg_patches:
            P = np.stack(self.bg_patches)
            m = P.reshape(len(P), -1).mean(axis=1)
            keep = m > 2.0
            norm = (P[keep] / m[keep, None, None]).reshape(int(keep.sum()), -1)
            out["bg_skewness"] = float(np.mean([_skew(v) for v in norm]))
            out["grey_p10"], out["grey_p90"] = (float(v) for v in np.percentile(norm, [10, 90]))
            out["low_freq_share"] = float(np.mean([_low_freq_share(p) for p in P[keep]]))
            out["bright_dim_corr"] = _bright_dim_corr(P, np.asarray(self.bg_patch_band))
        else:
            out.update(bg_skewness=np.nan, grey_p10=np.nan, grey_p90=np.nan, low_freq_share=np.nan,
                       bright_dim_corr=np.nan)
        out["arc_rows"] = 100.0 * float(np.mean(self.arc_rows)) if self.arc_rows else np.nan
        out["streak_beams"] = 100.0 * float(np.mean(self.streak_beams)) if self.streak_beams else np.nan
        if self.dark:
            far, near = np.mean(np.array(self.dark), axis=0)
            out["dark_far_near"] = float(far / near) if near > 0 else np.nan
        else:
            out["dark_far_near"] = np.nan
        objs = np.array(self.objects, dtype=float).reshape(-1, 4)
        out["object_p99_bg"] = float(np.median(objs[:, 1])) if len(objs) else np.nan
        out["object_len_range"] = float(np.median(objs[:, 2])) if len(objs) else np.nan
        standing = objs[objs[:, 0] == 8]
        out["standing_len_range"] = float(np.median(standing[:, 2])) if len(standing) else np.nan
        sh = objs[np.isfinite(objs[:, 3]), 3] if len(objs) else np.empty(0)
        out["shadow_share"] = 100.0 * float(np.mean(sh < SHADOW_RATIO)) if sh.size else np.nan
        return out

    def range_profile(self) -> NDArray[np.float64]:
        """(N_RANGE_BANDS,) mean grey per range band, near to far, over the set's mean."""
        prof = self.band_sum / np.maximum(self.band_n, 1)
        return prof / max(float(prof.mean()), 1e-9)


def _acf(s: NDArray, ok: NDArray[np.bool_], *, axis: int, max_lag: int) -> NDArray[np.float64]:
    """Autocorrelation of ``s`` along ``axis`` over pairs where both samples are ``ok``,
    lags 0..max_lag (normalised by lag 0)."""
    out = np.zeros(max_lag + 1)
    s = np.moveaxis(s, axis, 0)
    ok = np.moveaxis(ok, axis, 0)
    for k in range(max_lag + 1):
        a, b = s[:s.shape[0] - k], s[k:]
        m = ok[:ok.shape[0] - k] & ok[k:]
        out[k] = float((a[m] * b[m]).mean()) if m.any() else np.nan
    return out / out[0] if out[0] > 0 else out


def _mean_acf(acfs: list) -> NDArray[np.float64] | None:
    if not acfs:
        return None
    return np.nanmean(np.stack(acfs), axis=0)


def _fwhm(acf: NDArray[np.float64] | None) -> float:
    """Full width at half maximum of an autocorrelation sampled at integer lags, in lags."""
    if acf is None or not np.isfinite(acf[0]):
        return np.nan
    below = np.flatnonzero(acf < 0.5)
    if below.size == 0:
        return 2.0 * (len(acf) - 1)
    k = int(below[0])
    a0, a1 = acf[k - 1], acf[k]
    return float(2.0 * ((k - 1) + (a0 - 0.5) / (a0 - a1)))


def _peaked_share(v: NDArray, window: int) -> float:
    """Share of samples more than :data:`ARC_RATIO` above the running median of ``window``."""
    if v.size < window:
        return np.nan
    pad = window // 2
    vp = np.pad(v, pad, mode="edge")
    run = np.array([np.median(vp[i:i + window]) for i in range(v.size)])
    return float(np.mean(v > ARC_RATIO * np.maximum(run, 1.0)))


def _skew(v: NDArray) -> float:
    d = v - v.mean()
    s = d.std()
    return float((d ** 3).mean() / s ** 3) if s > 0 else 0.0


def _row_corr(patch: NDArray) -> float:
    """Lag-1 autocorrelation of a patch down its rows (along range near the fan's centre line),
    about the patch mean (:func:`_acf`); NaN for a flat patch."""
    d = patch.astype(np.float64) - patch.mean()
    acf = _acf(d, np.ones(d.shape, dtype=bool), axis=0, max_lag=1)
    return float(acf[1]) if acf[0] > 0 else np.nan


def _bright_dim_corr(patches: NDArray, bands: NDArray, min_per_band: int = 8) -> float:
    """Median over range bands of (median row-to-row correlation of the band's brighter half of
    background patches) / (that of its dimmer half), split at the band's median patch mean: 1
    when how correlated the floor looks does not depend on how bright it is; NaN without a band
    of ``min_per_band`` patches."""
    means = patches.reshape(len(patches), -1).mean(axis=1)
    corr = np.array([_row_corr(p) for p in patches])
    ratios = []
    for b in np.unique(bands):
        k = (bands == b) & np.isfinite(corr)
        if k.sum() < min_per_band:
            continue
        bright = means[k] > np.median(means[k])
        lo, hi = np.median(corr[k][~bright]), np.median(corr[k][bright])
        if lo > 0:
            ratios.append(hi / lo)
    return float(np.median(ratios)) if ratios else np.nan


def _low_freq_share(patch: NDArray) -> float:
    """Share of a patch's (mean-removed) spectral energy below 1/8 cycle per pixel."""
    p = patch - patch.mean()
    spec = np.abs(np.fft.fft2(p)) ** 2
    f = np.fft.fftfreq(p.shape[0])
    rad = np.hypot(f[:, None], f[None, :])
    tot = spec.sum()
    return float(spec[(rad > 0) & (rad < 0.125)].sum() / tot) if tot > 0 else 0.0
