"""Split a folder of labelled frames in the watertank layout into a training part and the rest.

For the sim-to-real comparisons (a detector trained on a few real frames, on most of them,
with and without synthetic pretraining, each scored on the frames it did not see): the frames
are shuffled with ``--seed`` and the first ``--train`` go to ``OUT/train``, the others to
``OUT/rest``, each a watertank-layout folder of symbolic links to the originals (``images/``,
``boxes/``, ``masks/`` and ``classes.txt`` where the source has them), so nothing is copied.
``OUT/split.json`` lists both parts' frame names.

Usage: ``python scripts/split_labelled_folder.py --data DIR --train 60 --seed 0 --out OUT``.
Bad input gets one line and exit status 2; an existing ``OUT`` is never overwritten.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

import numpy as np

PARTS = ("images", "boxes", "masks")


def split_folder(data: Path, n_train: int, seed: int, out: Path) -> dict[str, list[str]]:
    """Write ``out/train`` and ``out/rest`` (links) and ``out/split.json``; returns the split.

    Raises:
        ValueError: ``data`` is not a watertank-layout folder, ``n_train`` is not below its
            frame count, or ``out`` exists (one line each).
    """
    if not (data / "images").is_dir() or not (data / "boxes").is_dir():
        raise ValueError(f"--data {data}: not a watertank-layout folder (images/ and boxes/)")
    if out.exists():
        raise ValueError(f"--out {out}: exists; give a new folder")
    names = sorted(p.stem for p in (data / "images").glob("*.png"))
    if not 0 < n_train < len(names):
        raise ValueError(f"--train {n_train}: must be between 1 and {len(names) - 1} (the folder has "
                         f"{len(names)} frames)")
    order = np.random.default_rng(seed).permutation(len(names))
    split = {"train": sorted(names[i] for i in order[:n_train]), "rest": sorted(names[i] for i in order[n_train:])}
    for part, stems in split.items():
        for sub in PARTS:
            if not (data / sub).is_dir():
                continue
            (out / part / sub).mkdir(parents=True)
            ext = ".xml" if sub == "boxes" else ".png"
            for stem in stems:
                src = data / sub / f"{stem}{ext}"
                if src.exists():
                    os.symlink(src.resolve(), out / part / sub / f"{stem}{ext}")
        if (data / "classes.txt").is_file():
            os.symlink((data / "classes.txt").resolve(), out / part / "classes.txt")
    (out / "split.json").write_text(json.dumps({"data": str(data.resolve()), "seed": seed, **split}, indent=1))
    return split


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", required=True, help="watertank-layout folder (images/, boxes/, masks/)")
    ap.add_argument("--train", type=int, required=True, help="frames in the training part")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", required=True, help="new folder for train/, rest/ and split.json")
    args = ap.parse_args(argv)
    try:
        split = split_folder(Path(args.data), args.train, args.seed, Path(args.out))
    except ValueError as exc:
        print(f"split_labelled_folder: {exc}", file=sys.stderr)
        return 2
    print(f"split_labelled_folder: {len(split['train'])} frames in {args.out}/train, {len(split['rest'])} in "
          f"{args.out}/rest")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
