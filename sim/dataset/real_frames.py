"""Real forward-looking sonar frames read from a folder, and the fan outline fitted to them.

The folder layout is the one the Marine Debris water-tank release uses
([MarineDebrisFLS] in ``docs/references.md``): ``images/NAME.png`` (one-channel uint8 fan
images, apex at the bottom centre, black outside the fan), optionally ``masks/NAME.png``
(uint8 class id per pixel, 0 background) and ``boxes/NAME.xml`` (Pascal-VOC-like XML whose
``bndbox`` holds ``x y w h``). Nothing of the data is stored by the project: code takes the
folder as an argument.

The fan outline (apex, near and far arc radii, half-angle) is fitted to the pixels that are
non-zero in most frames: two straight edges through the apex (least squares on each row's
first and last lit pixel), then the arcs' radii from the apex (medians over the columns the
arcs span). A metric scale needs one range: the near edge of the window (``near_m``).

A set may mix recordings made with different range windows, whose fans differ in the
exported image (the Marine Debris development split holds two: 367 and 233 of its 600
frames). :func:`fan_groups` sorts the frames by their own fan's outline (top and bottom of
the centre columns, left and right edges at mid height), so that a fit and every measure
use frames of one fan.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from autonomy.sonar_geometry import FanGeometry

#: Class ids of the Marine Debris water-tank masks ([MarineDebrisFLS]); 0 is background.
MARINE_DEBRIS_CLASSES: dict[int, str] = {
    1: "Bottle", 2: "Can", 3: "Chain", 4: "Drink-carton", 5: "Hook", 6: "Propeller", 7: "Shampoo-bottle",
    8: "Standing-bottle", 9: "Tire", 10: "Valve", 11: "Wall"}
WALL_CLASS_ID = 11


class RealDataError(ValueError):
    """A real-frame folder that cannot be read; the message is one line naming the path."""


@dataclass(frozen=True)
class RealBox:
    """One labelled instance: class name and its ``(x, y, w, h)`` box, px."""

    class_name: str
    xywh: tuple[int, int, int, int]


@dataclass(frozen=True)
class RealFrames:
    """A set of real fan images (and their labels where the folder has them).

    Attributes:
        names: (N,) frame names (file stems).
        images: (N, H, W) uint8 fan images.
        masks: (N, H, W) uint8 class ids, or None when the folder has no ``masks``.
        boxes: per frame, its labelled boxes (empty tuples when the folder has no ``boxes``).
    """

    names: tuple[str, ...]
    images: NDArray[np.uint8]
    masks: NDArray[np.uint8] | None
    boxes: tuple[tuple[RealBox, ...], ...]


def natural_key(path: Path) -> tuple:
    """Sort key of a frame file: its name with runs of digits compared as numbers (frame-2 before frame-10)."""
    return tuple(int(t) if t.isdigit() else t for t in re.split(r"(\d+)", path.stem))


def read_frame(path: Path, first: NDArray[np.uint8] | None = None) -> NDArray[np.uint8]:
    """One grey frame; ``first``: the set's first frame, whose size it must have.

    Raises:
        RealDataError: not a readable image, or another size than ``first``.
    """
    img = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    if img is None:
        raise RealDataError(f"{path}: not a readable image")
    if first is not None and img.shape != first.shape:
        raise RealDataError(f"{path}: {img.shape[1]} x {img.shape[0]} px, the first image is "
                            f"{first.shape[1]} x {first.shape[0]}; all frames must have one size")
    return img


def load_real_frames(folder: str | Path, *, limit: int | None = None) -> RealFrames:
    """Read the frames of ``folder`` (layout in the module docstring), in natural name order.

    Args:
        folder: the set's root (holding ``images/``), or a folder of PNGs itself.
        limit: read at most this many frames (the first ones).

    Raises:
        RealDataError: the folder, its images or a label file is missing or unreadable, or
            the images differ in size.
    """
    root = Path(folder)
    if not root.is_dir():
        raise RealDataError(f"--real {root}: no such folder (give the folder that holds images/*.png)")
    img_dir = root / "images" if (root / "images").is_dir() else root
    paths = sorted(img_dir.glob("*.png"), key=natural_key)
    if not paths:
        raise RealDataError(f"--real {root}: no PNG images in {img_dir}")
    if limit is not None:
        paths = paths[:max(int(limit), 1)]
    mask_dir, box_dir = root / "masks", root / "boxes"
    has_masks, has_boxes = mask_dir.is_dir(), box_dir.is_dir()
    images, masks, boxes = [], [], []
    for p in paths:
        img = read_frame(p, images[0] if images else None)
        images.append(img)
        if has_masks:
            mp = mask_dir / p.name
            m = cv2.imread(str(mp), cv2.IMREAD_GRAYSCALE) if mp.is_file() else None
            if m is None or m.shape != img.shape:
                raise RealDataError(f"{mp}: missing, unreadable or not the size of its image")
            masks.append(m)
        boxes.append(read_box_file(box_dir / f"{p.stem}.xml") if has_boxes else ())
    return RealFrames(names=tuple(p.stem for p in paths), images=np.stack(images),
                      masks=np.stack(masks) if has_masks else None, boxes=tuple(boxes))


def read_box_file(path: Path) -> tuple[RealBox, ...]:
    """The ``object`` entries of one box file (``x y w h`` in px); a missing file: none.

    Raises:
        RealDataError: a file that is not XML with ``object/name`` and ``bndbox x y w h``.
    """
    if not path.exists():
        return ()
    try:
        root = ET.parse(path).getroot()
        out = []
        for obj in root.iter("object"):
            b = obj.find("bndbox")
            out.append(RealBox(str(obj.findtext("name")), tuple(int(float(b.findtext(k))) for k in "xywh")))
        return tuple(out)
    except (ET.ParseError, AttributeError, TypeError, ValueError) as exc:
        raise RealDataError(f"{path}: not a box file with object/bndbox x y w h ({exc})") from None


@dataclass(frozen=True)
class FanOutline:
    """The fan of a set of images, in pixels.

    Attributes:
        width_px, height_px: image size.
        apex_x_px, apex_y_px: the sonar head (the edges' crossing; may lie below the image).
        near_px, far_px: radii of the near and far arcs from the apex.
        half_angle_rad: half the field of view (mean of the two edges).
        edge_rms_px: rms residual of the edge and arc fits.
    """

    width_px: int
    height_px: int
    apex_x_px: float
    apex_y_px: float
    near_px: float
    far_px: float
    half_angle_rad: float
    edge_rms_px: float

    @property
    def near_far_ratio(self) -> float:
        return self.near_px / self.far_px

    def geometry(self, near_m: float) -> FanGeometry:
        """The fan as a :class:`FanGeometry` whose window starts at ``near_m`` (m): the far
        range is ``near_m / near_far_ratio`` and one pixel ``near_m / near_px`` metres."""
        m_per_px = near_m / self.near_px
        return FanGeometry(self.width_px, self.height_px, float(near_m), float(self.far_px * m_per_px),
                           float(2.0 * self.half_angle_rad), float(m_per_px), self.apex_x_px, self.apex_y_px)


#: Frames whose outline signatures differ by at most this (px, each of the four) share a fan.
FAN_GROUP_TOL_PX = 6


def fan_signature(image: NDArray[np.uint8]) -> NDArray[np.int64]:
    """(4,) the lit outline of one frame, px: first and last lit row of the centre columns,
    first and last lit column of the middle row (-1 where nothing is lit)."""
    lit = image > 0
    h, w = lit.shape
    rows = np.flatnonzero(lit[:, max(w // 2 - 10, 0):w // 2 + 10].any(axis=1))
    cols = np.flatnonzero(lit[h // 2 - 2:h // 2 + 3].any(axis=0))
    return np.array([rows[0] if rows.size else -1, rows[-1] if rows.size else -1,
                     cols[0] if cols.size else -1, cols[-1] if cols.size else -1], dtype=np.int64)


def fan_groups(images: NDArray[np.uint8], tol_px: int = FAN_GROUP_TOL_PX) -> list[NDArray[np.intp]]:
    """Frame indices grouped by fan outline (:func:`fan_signature`), largest group first:
    each group gathers the frames within ``tol_px`` of the most common remaining signature."""
    sig = np.array([fan_signature(im) for im in images])
    left = np.arange(len(images))
    groups = []
    while left.size:
        keys, counts = np.unique(sig[left] // 2, axis=0, return_counts=True)
        seed = keys[np.argmax(counts)] * 2
        near = np.all(np.abs(sig[left] - seed) <= tol_px, axis=1)
        groups.append(left[near])
        left = left[~near]
    return sorted(groups, key=len, reverse=True)


def fit_fan_outline(images: NDArray[np.uint8], *, lit_share: float = 0.5) -> FanOutline:
    """Fit the fan outline to ``images`` (N, H, W) of one fan (:func:`fan_groups`): the pixels
    non-zero in more than ``lit_share`` of the frames.

    Raises:
        RealDataError: the lit pixels do not form a fan: fewer than 20 lit rows, edges that
            do not meet below the top of the image, a half-angle outside 2-80 deg, a near
            arc not inside the far one, or edges that are not straight (rms above 3 px).
    """
    lit = (images > 0).mean(axis=0) > lit_share
    h, w = lit.shape
    rows = np.flatnonzero(lit.any(axis=1))
    not_fan = "real frames: no sonar fan found (the pixels lit in most frames must form a fan: apex below, " \
              "far arc above, black outside)"
    if rows.size < 20:
        raise RealDataError(f"{not_fan}; fewer than 20 rows are lit")
    top, bottom = rows[0], rows[-1]
    span = bottom - top
    ys = np.arange(top + span // 8, bottom - span // 8)
    ys = ys[lit[ys].any(axis=1)]
    left = np.array([np.flatnonzero(lit[y])[0] - 0.5 for y in ys])
    right = np.array([np.flatnonzero(lit[y])[-1] + 0.5 for y in ys])
    pl, pr = np.polyfit(ys, left, 1), np.polyfit(ys, right, 1)
    if not (pl[0] > 1e-3 and pr[0] < -1e-3):  # going down the image, both edges close in on the apex
        raise RealDataError(f"{not_fan}; its side edges do not converge downwards")
    apex_y = (pr[1] - pl[1]) / (pl[0] - pr[0])
    apex_x = 0.5 * (np.polyval(pl, apex_y) + np.polyval(pr, apex_y))
    half = 0.5 * (abs(np.arctan(pl[0])) + abs(np.arctan(pr[0])))
    res = np.concatenate([left - np.polyval(pl, ys), right - np.polyval(pr, ys)])
    far_pts, near_pts = [], []
    for x in range(w):
        col = np.flatnonzero(lit[:, x])
        if col.size == 0:
            continue
        far_pts.append((x, np.hypot(x - apex_x, col[0] - 0.5 - apex_y)))
        near_pts.append((x, np.hypot(x - apex_x, col[-1] + 0.5 - apex_y)))
    far_pts, near_pts = np.array(far_pts), np.array(near_pts)
    far_px = float(np.median(far_pts[np.abs(far_pts[:, 0] - apex_x) < 0.8 * far_pts[:, 1].max() * np.sin(half), 1]))
    # the near arc spans only the columns within its own half-width of the apex
    near_guess = float(np.min(near_pts[:, 1]))
    on_near = np.abs(near_pts[:, 0] - apex_x) < 0.8 * near_guess * np.sin(half)
    near_px = float(np.median(near_pts[on_near, 1]))
    res = np.concatenate([res, far_pts[:, 1][np.abs(far_pts[:, 0] - apex_x) < 0.8 * far_px * np.sin(half)] - far_px,
                          near_pts[on_near, 1] - near_px])
    rms = float(np.sqrt(np.mean(res ** 2)))
    if not (np.radians(2.0) <= half <= np.radians(80.0) and apex_y > top and 0.0 < near_px < far_px and rms <= 3.0):
        raise RealDataError(f"{not_fan}; the fit gives half-angle {np.degrees(half):.1f} deg, near/far "
                            f"{near_px:.0f}/{far_px:.0f} px, edge rms {rms:.1f} px")
    return FanOutline(int(w), int(h), float(apex_x), float(apex_y), near_px, far_px, float(half), rms)
