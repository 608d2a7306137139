"""The error raised for dataset folders and dataset requests a user got wrong."""

from __future__ import annotations

import json
from pathlib import Path


class DatasetError(ValueError):
    """A dataset folder is missing, incomplete, foreign, or made with other parameters.

    The message names the folder or argument and what is allowed.
    """


def require_dataset(path: str | Path, arg: str = "--data") -> Path:
    """A finished dataset folder written by ``auvsim dataset``, or a labelled folder in the
    watertank layout (``images/`` and ``boxes/``, :mod:`sim.dataset.labelled_folder`); returns
    it resolved.

    Raises:
        DatasetError: ``path`` does not exist, is not a folder, or has neither
            ``annotations.json`` (not a dataset, or generation did not finish) nor the
            watertank layout.
    """
    from sim.dataset.coco_io import ANNOTATIONS_FILE

    p = Path(path).expanduser()
    if not str(path).strip():
        raise DatasetError(f"{arg}: must name a dataset folder, got an empty string")
    if not p.exists():
        raise DatasetError(f"{arg} {p}: no such folder")
    if not p.is_dir():
        raise DatasetError(f"{arg} {p}: is a file, expected a dataset folder written by `auvsim dataset`")
    ann = p / ANNOTATIONS_FILE
    if not ann.is_file() and (p / "images").is_dir() and (p / "boxes").is_dir():
        return p.resolve()  # the watertank layout (sim.dataset.labelled_folder)
    if not ann.is_file() and (p / "images").is_dir():
        raise DatasetError(f"{arg} {p}: has images/ but neither boxes/ (the watertank layout: boxes/<stem>.xml per "
                           f"image) nor {ANNOTATIONS_FILE} (a dataset written by `auvsim dataset`)")
    if not ann.is_file() and (p / "manifest.json").is_file():
        raise DatasetError(f"{arg} {p}: an `auvsim dataset` folder whose generation did not finish (no "
                           f"{ANNOTATIONS_FILE} yet); rerun `auvsim dataset` with the same arguments to complete it")
    if not ann.is_file():
        inside = " (it is an images/ folder: give the folder that holds it)" if p.name == "images" else ""
        raise DatasetError(f"{arg} {p}: not a labelled folder: expected {ANNOTATIONS_FILE} (a dataset written by "
                           f"`auvsim dataset`) or images/ and boxes/ (the watertank layout of real frames){inside}")
    try:
        doc = json.loads(ann.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise DatasetError(f"{arg} {ann}: not a readable COCO JSON file ({exc}); regenerate the dataset") from None
    missing = [k for k in ("images", "annotations", "categories") if not isinstance(doc, dict) or k not in doc]
    if missing:
        raise DatasetError(f"{arg} {ann}: not a COCO detection file (missing {', '.join(missing)}); regenerate "
                           "the dataset")
    return p.resolve()


def fls_fan_hw(path: str | Path, arg: str = "--data") -> tuple[int, int]:
    """The (height, width) px of the forward-looking-sonar fans of a dataset folder (one
    :func:`require_dataset` accepted).

    Raises:
        DatasetError: the folder holds no image, images that are not FLS fans (side-scan
            tiles: no ``fan_geometry``), or fans of several sizes.
    """
    from sim.dataset.coco_io import ANNOTATIONS_FILE

    p = Path(path)
    if not (p / ANNOTATIONS_FILE).is_file():  # the watertank layout: its PNGs' size (one size, checked on loading)
        import cv2

        first = next(iter(sorted((p / "images").glob("*.png"))), None)
        img = cv2.imread(str(first), cv2.IMREAD_GRAYSCALE) if first is not None else None
        if img is None:
            raise DatasetError(f"{arg} {p}: no readable PNG image in images/")
        return int(img.shape[0]), int(img.shape[1])
    images = json.loads((p / ANNOTATIONS_FILE).read_text())["images"]
    if not images:
        raise DatasetError(f"{arg} {p}: the dataset holds no images")
    if any("fan_geometry" not in im for im in images):
        kind = "side-scan tiles" if any("sss_geometry" in im for im in images) else "images without a fan_geometry"
        raise DatasetError(f"{arg} {p}: holds {kind}, not forward-looking sonar fans (auvsim dataset --sensor fls)")
    sizes = sorted({(int(im["height"]), int(im["width"])) for im in images})
    if len(sizes) > 1:
        raise DatasetError(f"{arg} {p}: fans of {len(sizes)} sizes ({', '.join(f'{w} x {h}' for h, w in sizes)} px); "
                           "a dataset holds one sonar's fans")
    return sizes[0]
