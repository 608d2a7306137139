"""Draw a page of labelled frames with their boxes, from a dataset or real labelled frames.

Any labelled folder: a dataset of ``auvsim dataset`` (a spec's or the survey presets') or real
frames in the watertank layout.

Usage: ``python scripts/dataset_preview.py --data DIR --out PAGE.png [--frames 8] [--columns 4] [--scale 1]``.
Bad input gets one line and exit status 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

from sim.dataset.errors import DatasetError
from sim.dataset.labelled_folder import load_labelled_folder

#: Box colours (BGR) by category id, cycled.
COLOURS = ((80, 220, 80), (60, 200, 255), (255, 160, 60), (200, 90, 255), (90, 255, 255), (255, 90, 90))


def preview(data: str, out: Path, frames: int = 8, columns: int = 4, scale: float = 1.0) -> Path:
    """Draw the first ``frames`` labelled frames of ``data`` (boxes and class names; ``iscrowd``
    boxes grey) in a grid of ``columns`` and write ``out`` (PNG).

    Raises:
        DatasetError: ``data`` is not a labelled folder (one line).
    """
    folder = load_labelled_folder(data)
    names = {c["id"]: c["name"] for c in folder.coco["categories"]}
    tiles = []
    for rec in sorted(folder.coco["images"], key=lambda r: r["id"])[:frames]:
        img = cv2.cvtColor(folder.image(rec), cv2.COLOR_GRAY2BGR)
        for a in folder.coco["annotations"]:
            if a["image_id"] != rec["id"]:
                continue
            x, y, w, h = (int(round(v)) for v in a["bbox"])
            colour = (140, 140, 140) if a.get("iscrowd") else COLOURS[(a["category_id"] - 1) % len(COLOURS)]
            cv2.rectangle(img, (x, y), (x + w - 1, y + h - 1), colour, 1)
            cv2.putText(img, names[a["category_id"]], (x, max(y - 3, 9)), cv2.FONT_HERSHEY_SIMPLEX, 0.35, colour, 1,
                        cv2.LINE_AA)
        cv2.putText(img, Path(rec["file_name"]).name, (4, img.shape[0] - 6), cv2.FONT_HERSHEY_SIMPLEX, 0.35,
                    (255, 255, 255), 1, cv2.LINE_AA)
        tiles.append(img)
    if not tiles:
        raise DatasetError(f"--data {data}: no frames to draw")
    h, w = tiles[0].shape[:2]
    rows = -(-len(tiles) // columns)
    page = np.zeros((rows * h, min(columns, len(tiles)) * w, 3), np.uint8)
    for k, t in enumerate(tiles):
        r, c = divmod(k, columns)
        page[r * h:(r + 1) * h, c * w:(c + 1) * w] = t
    if scale != 1.0:
        page = cv2.resize(page, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    cv2.imwrite(str(out), page, [cv2.IMWRITE_PNG_COMPRESSION, 9])
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", required=True, help="labelled folder (annotations.json, or images/ and boxes/)")
    ap.add_argument("--out", required=True, help="the page, a .png file")
    ap.add_argument("--frames", type=int, default=8, help="frames drawn (1 to 64)")
    ap.add_argument("--columns", type=int, default=4, help="frames per row (1 to 16)")
    ap.add_argument("--scale", type=float, default=1.0, help="page size factor (0.1 to 1)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    problem = (f"--out {out}: must be a .png file" if out.suffix.lower() != ".png" else
               f"--out {out}: its folder does not exist" if not out.parent.is_dir() else
               f"--frames {args.frames}: allowed 1 to 64" if not 1 <= args.frames <= 64 else
               f"--columns {args.columns}: allowed 1 to 16" if not 1 <= args.columns <= 16 else
               f"--scale {args.scale}: allowed 0.1 to 1" if not 0.1 <= args.scale <= 1.0 else None)
    if problem:
        print(f"dataset_preview: {problem}", file=sys.stderr)
        return 2
    try:
        preview(args.data, out, args.frames, args.columns, args.scale)
    except DatasetError as exc:
        print(f"dataset_preview: {exc}", file=sys.stderr)
        return 2
    print(f"dataset_preview: wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
