"""A labelled folder in the watertank layout split into a training part and the rest, as
folders of symbolic links (nothing copied): for training on some real frames and scoring on
the others (``scripts/split_labelled_folder.py``, ``scripts/sim_to_real.py``)."""

from __future__ import annotations

import json
import os
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
