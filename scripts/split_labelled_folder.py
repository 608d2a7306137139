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
import sys
from pathlib import Path

from sim.dataset.split import split_folder


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", required=True, help="watertank-layout folder (images/, boxes/, masks/)")
    ap.add_argument("--train", type=int, required=True, help="frames in the training part")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", required=True, help="new folder for train/, rest/ and split.json")
    ap.add_argument("--by", choices=("frame", "scene"), default="frame",
                    help="frame (default): a random draw of frames; scene: whole scenes (near-copies together)")
    args = ap.parse_args(argv)
    try:
        split = split_folder(Path(args.data), args.train, args.seed, Path(args.out), by=args.by)
    except ValueError as exc:
        print(f"split_labelled_folder: {exc}", file=sys.stderr)
        return 2
    print(f"split_labelled_folder: {len(split['train'])} frames in {args.out}/train, {len(split['rest'])} in "
          f"{args.out}/rest")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
