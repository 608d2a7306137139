"""A labelled folder in the watertank layout split into a training part and the rest, as
folders of symbolic links (nothing copied): for training on some real frames and scoring on
the others (``scripts/split_labelled_folder.py``, ``scripts/sim_to_real.py``).

Frames of one recording are often near-copies of each other: in the Marine Debris
development split 94 % of the frames have a nearest neighbour closer than half the median
distance between two frames, and their file numbers are not in time order. A random split
by frame then scores a model on near-copies of its training frames. ``by="scene"`` keeps such
frames together (:func:`scene_groups`), so the rest holds scenes the training part never
showed.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

PARTS = ("images", "boxes", "masks")


#: Frames closer than this fraction of the median distance between two frames of the folder
#: (rms grey difference of 80 x 120 thumbnails) are one scene; scenes are the connected groups.
SCENE_LINK = 0.35


def scene_groups(images: list[Path], link: float = SCENE_LINK) -> np.ndarray:
    """Scene label (N,) of each image: single-linkage groups of frames whose thumbnails' rms
    grey difference is below ``link`` times the median over all pairs."""
    import cv2
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components

    x = np.stack([cv2.resize(cv2.imread(str(p), cv2.IMREAD_GRAYSCALE).astype(np.float64), (80, 120),
                             interpolation=cv2.INTER_AREA).ravel() for p in images])
    sq = np.einsum("ij,ij->i", x, x)
    d = np.sqrt(np.maximum(sq[:, None] + sq[None, :] - 2.0 * x @ x.T, 0.0) / x.shape[1])
    np.fill_diagonal(d, np.inf)
    med = float(np.median(d[np.isfinite(d)])) if len(images) > 1 else 0.0
    return connected_components(csr_matrix(d < link * med), directed=False)[1]


def split_folder(data: Path, n_train: int, seed: int, out: Path, by: str = "frame") -> dict[str, list[str]]:
    """Write ``out/train`` and ``out/rest`` (links) and ``out/split.json``; returns the split.

    ``by``: ``frame`` (a random draw of frames) or ``scene`` (random whole scenes,
    :func:`scene_groups`, until ``n_train`` frames: the largest scenes that fit first in a
    random order, then smaller ones to make the count exact where they allow).

    Raises:
        ValueError: ``data`` is not a watertank-layout folder, ``n_train`` is not below its
            frame count, ``by`` is neither, or ``out`` exists (one line each).
    """
    if not (data / "images").is_dir() or not (data / "boxes").is_dir():
        raise ValueError(f"--data {data}: not a watertank-layout folder (images/ and boxes/)")
    if out.exists():
        raise ValueError(f"--out {out}: exists; give a new folder")
    names = sorted(p.stem for p in (data / "images").glob("*.png"))
    if not 0 < n_train < len(names):
        raise ValueError(f"--train {n_train}: must be between 1 and {len(names) - 1} (the folder has "
                         f"{len(names)} frames)")
    rng = np.random.default_rng(seed)
    if by == "frame":
        order = rng.permutation(len(names))
        chosen = [names[i] for i in order[:n_train]]
    elif by == "scene":
        label = scene_groups([data / "images" / f"{n}.png" for n in names])
        chosen = []
        for g in rng.permutation(int(label.max()) + 1):
            members = [names[i] for i in np.flatnonzero(label == g)]
            if len(chosen) + len(members) <= n_train:
                chosen += members
            if len(chosen) == n_train:
                break
    else:
        raise ValueError(f"--split-by {by!r}: allowed: frame, scene")
    taken = set(chosen)
    split = {"train": sorted(chosen), "rest": sorted(n for n in names if n not in taken)}
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
    (out / "split.json").write_text(json.dumps({"data": str(data.resolve()), "seed": seed, "by": by, **split},
                                               indent=1))
    return split
