"""Dataset specs: the shipped ones load and the survey ones are the randomisation presets; a bad
spec is refused in one line naming the file and key; a tank spec renders labelled frames on its
fan grid, the same for the same seed, in the watertank layout that reads back as written."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from sim.dataset.errors import DatasetError
from sim.dataset.generate import RenderSettings, _manifest, generation_args
from sim.dataset.labelled_folder import load_labelled_folder
from sim.dataset.randomization import RANDOMIZATION_PRESETS
from sim.dataset.spec import load_spec, shipped_specs
from tests.support import assert_clean_error, run_cli

TANK_SPEC = """
name: tiny_tank
scene:
  kind: tank
  objects: [2, 3]
  wall_share: 0.5
  catalogue:
    - {class_name: bottle, shape: bottle, weight: 2}
    - {class_name: tyre, shape: tyre}
sonar:
  preset: aris3000
  elevation_rays: 16
  settings: {gain_db: 12.0}
image: {width_px: 160, height_px: 240, apex_x_px: 79.7, apex_y_px: 301.3, fov_deg: 30.0, near_m: 0.7,
        far_m: 2.9, m_per_px: 0.0100}
formats: [coco, watertank]
"""


def test_shipped_specs_load_and_the_survey_ones_are_the_presets():
    assert set(shipped_specs()) >= {"fls_train", "fls_wide", "fls_heldout", "marine_debris_watertank"}
    for name in ("train", "wide", "heldout"):
        args = generation_args(load_spec(f"fls_{name}"))
        assert args["randomization"] == RANDOMIZATION_PRESETS[name]
        assert args["settings"] == RenderSettings()
        # the same manifest, so the same dataset, as `auvsim dataset --randomization NAME`
        assert _manifest(10, 3, args["randomization"], args["settings"]) == \
            _manifest(10, 3, RANDOMIZATION_PRESETS[name], RenderSettings())
    tank = load_spec("marine_debris_watertank")
    assert tank.scene.class_names()[-1] == "Wall" and len(tank.scene.class_names()) == 11
    from sim.dataset.tank_scenes import TANK_FORMATION_SHELLS

    assert tank.sonar.settings["formation"] == TANK_FORMATION_SHELLS["formation"]  # the formation named in docs
    g = tank.image.geometry()
    assert (g.width_px, g.height_px) == (320, 480) and g.range_max_m == pytest.approx(2.913)


@pytest.mark.parametrize("edit, culprits", [
    (lambda t: t.replace("name: tiny_tank", "name: tiny_tank\ncolour: red"), ["colour", "unknown key"]),
    (lambda t: t.replace("shape: tyre", "shape: tire"), ["scene.catalogue.1.shape", "tyre"]),
    (lambda t: t.replace("elevation_rays: 16", "azimuth_columns: 361"), ["sonar", "n_beams (128)"]),
    (lambda t: t.replace("gain_db: 12.0", "gain: 12.0"), ["sonar.settings.gain", "not a forward-looking sonar"]),
    (lambda t: t.replace("[coco, watertank]", "[watertank]"), ["formats", "coco is always written"]),
    (lambda t: t.replace("objects: [2, 3]", "objects: [3, 2]"), ["objects", "lower bound"]),
    (lambda t: t.replace("kind: tank", "kind: lake"), ["scene", "seabed", "tank"]),
    (lambda t: t.replace("far_m: 2.9", "far_m: 4.0"), ["far_m", "above the image"]),
    (lambda t: t.replace("objects: [2, 3]", "objects: [2, 3]\n  object_range_m: [1.0, 3.5]"),
     ["scene.object_range_m", "beyond the window"]),
    (lambda t: t.replace("objects: [2, 3]", "objects: [2, 3]\n  height_m: [0.2, 3.0]"), ["scene.height_m", "no floor"]),
    (lambda t: t.replace("objects: [2, 3]", "objects: [2, 3]\n  tilt_deg: 15"), ["scene.tilt_deg", "[low, high] pair"]),
    (lambda t: t.replace("name: tiny_tank", "name: [tiny_tank"), ["not a readable YAML file", "line"]),
    (lambda t: "- just a list\n", ["a YAML mapping"]),
    (lambda t: t.replace("shape: tyre}", "shape: tyre, size_scale: [0.01, 2]}"), ["catalogue.1.size_scale", "0.05"]),
    (lambda t: t.replace("settings: {gain_db: 12.0}", "settings: {gain_db: 12.0}\n  randomize: {gain: [0, 6]}"),
     ["sonar.randomize.gain", "did you mean gain_db?"]),
    (lambda t: t.replace("settings: {gain_db: 12.0}", "settings: {gain_db: 12.0}\n  randomize: "
                         "{formation.object_back_wall_ratio: [0.2, 1.5]}"),
     ["sonar.randomize.formation.object_back_wall_ratio", "bound 1.5", "less than or equal to 1"]),
    (lambda t: t.replace("settings: {gain_db: 12.0}", "settings: {gain_db: 12.0}\n  randomize: "
                         "{formation.object_back_wall_repeats: [1, 2.5]}"),
     ["randomize.formation.object_back_wall_repeats", "whole-number bounds"]),
    (lambda t: t.replace("settings: {gain_db: 12.0}", "settings: {gain_db: 12.0}\n  randomize: {gain_db: [6, 0]}"),
     ["randomize.gain_db", "lower bound"]),
    (lambda t: t.replace("settings: {gain_db: 12.0}", "settings: {gain_db: 12.0}\n  randomize: {tilt_deg: [5, 9]}"),
     ["randomize.tilt_deg", "scene.tilt_deg"]),
    (lambda t: t.replace("settings: {gain_db: 12.0}", "settings: {gain_db: 12.0}\n  randomize: {rate_hz: [1, 5]}"),
     ["randomize.rate_hz", "no effect"]),
    (lambda t: t.replace("settings: {gain_db: 12.0}", "settings: {gain_db: 12.0}\n  randomize: "
                         "{formation.beam_correlated_speckle: [0, 1]}"),
     ["randomize.formation.beam_correlated_speckle", "not a numeric setting"]),
    (lambda t: t.replace("settings: {gain_db: 12.0}", "settings: {gain_db: 12.0}\n  randomize: {gain_db: [true, 20]}"),
     ["randomize.gain_db", "a [low, high] pair of numbers"]),
    (lambda t: t.replace("settings: {gain_db: 12.0}", "settings: {gain_db: 12.0}\n  randomize: "
                         "{pulse_length_m: [0.01, 0.02]}"),
     ["randomize.pulse_length_m", "did you mean formation.pulse_length_m?"]),
])
def test_a_bad_spec_is_refused_in_one_line_naming_the_key(tmp_path, edit, culprits):
    path = tmp_path / "spec.yaml"
    path.write_text(edit(TANK_SPEC))
    with pytest.raises(DatasetError) as exc:
        load_spec(path)
    msg = str(exc.value)
    assert "\n" not in msg and str(path) in msg
    for c in culprits:
        assert c in msg, msg


def test_a_seabed_spec_changes_ranges_of_its_preset_and_refuses_unknown_ones(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text("name: deep\nscene: {kind: seabed, randomization: wide, ranges: {altitude_m: [4.0, 8.0]}}\n"
                    "sonar: {preset: m900_130, elevation_rays: 16, azimuth_columns: 361}\n")
    rz = generation_args(load_spec(path))["randomization"]
    assert rz.altitude_m == (4.0, 8.0) and rz.noise_scale == RANDOMIZATION_PRESETS["wide"].noise_scale
    path.write_text("name: deep\nscene: {kind: seabed, ranges: {altitude: [4.0, 8.0]}}\n")
    with pytest.raises(DatasetError, match="ranges.altitude: not a randomisation range"):
        load_spec(path)


def test_a_tank_spec_renders_labelled_frames_the_same_for_the_same_seed(tmp_path):
    from sim.dataset.generate import generate_dataset

    spec_path = tmp_path / "tank.yaml"
    spec_path.write_text(TANK_SPEC)
    args = generation_args(load_spec(spec_path))
    a = generate_dataset(tmp_path / "a", 4, seed=5, workers=1, progress=False, **args).parent
    coco = json.loads((a / "annotations.json").read_text())
    assert [c["name"] for c in coco["categories"]] == ["bottle", "tyre", "Wall"]  # classes of one's own
    assert len(coco["images"]) == 4 and {im["width"] for im in coco["images"]} == {160}
    assert {a_["category_id"] for a_ in coco["annotations"]} >= {3}  # a wall in some scenes
    assert not (a / "labels").exists()  # no yolo in its formats
    for ann in coco["annotations"]:  # an object on the floor within the window, box inside the image
        x, y, w, h = ann["bbox"]
        assert 0 <= x and x + w <= 160 and 0 <= y and y + h <= 240
        assert 0.6 <= ann["attributes"]["range_m"] <= 3.0
    # the same seed, the same bytes; a scene rendered again (resume) is the same too
    b = generate_dataset(tmp_path / "b", 4, seed=5, workers=1, progress=False, **args).parent
    for rel in ["annotations.json"] + [im["file_name"] for im in coco["images"]]:
        assert (a / rel).read_bytes() == (b / rel).read_bytes(), rel
    (b / "parts" / "scene_00001.json").unlink()
    generate_dataset(b, 4, seed=5, workers=1, progress=False, **args)
    assert (a / "annotations.json").read_bytes() == (b / "annotations.json").read_bytes()
    # the watertank layout (boxes, class masks, class names) reads back as the COCO labels say
    wt = tmp_path / "wt"
    for sub in ("images", "boxes", "masks"):
        shutil.copytree(a / sub, wt / sub)
    with pytest.raises(DatasetError, match="classes.txt"):  # without its class list: the Marine Debris classes
        load_labelled_folder(wt)
    shutil.copy(a / "classes.txt", wt / "classes.txt")
    back = load_labelled_folder(wt)
    names = {c["id"]: c["name"] for c in coco["categories"]}
    want = sorted((im, names[c], tuple(b_)) for im, c, b_, crowd in
                  ((x["image_id"], x["category_id"], x["bbox"], x["iscrowd"]) for x in coco["annotations"]) if not crowd)
    got = sorted((x["image_id"], {c["id"]: c["name"] for c in back.coco["categories"]}[x["category_id"]],
                  tuple(x["bbox"])) for x in back.coco["annotations"])
    assert got == want
    mask = np.array(__import__("cv2").imread(str(wt / "masks" / "000001.png"), 0))
    assert set(np.unique(mask)) <= {0, 1, 2, 3} and (mask == 3).any()


def test_a_tank_spec_draws_its_randomized_settings_per_scene(tmp_path):
    import cv2

    from sim.dataset.generate import generate_dataset

    spec_path = tmp_path / "tank.yaml"
    spec_path.write_text(TANK_SPEC.replace("settings: {gain_db: 12.0}", "settings: {gain_db: 12.0}\n  randomize: "
                                           "{gain_db: [0.0, 24.0], formation.object_back_wall_repeats: [1, 3]}"))
    spec = load_spec(spec_path)
    d = generate_dataset(tmp_path / "r", 6, seed=5, workers=1, progress=False, **generation_args(spec)).parent
    coco = json.loads((d / "annotations.json").read_text())
    drawn = [im["sonar"]["randomized"] for im in coco["images"]]
    assert all(0.0 <= r["gain_db"] <= 24.0 for r in drawn)
    assert all(r["formation.object_back_wall_repeats"] in (1, 2, 3) for r in drawn)
    assert len({r["gain_db"] for r in drawn}) == 6  # one draw per scene
    # the same scenes without randomize (gain 12 dB): each frame is brighter exactly when its
    # drawn gain is above 12 dB (scenes, speckle and poses come from other generators)
    spec_path.write_text(TANK_SPEC)
    plain_spec = load_spec(spec_path)
    assert plain_spec.sonar.draw(np.random.default_rng(0)) == {}  # nothing drawn, frames as before
    p = generate_dataset(tmp_path / "p", 6, seed=5, workers=1, progress=False, **generation_args(plain_spec)).parent
    assert "randomized" not in json.loads((p / "annotations.json").read_text())["images"][0]["sonar"]

    def grey(folder, im):
        return float(np.mean(cv2.imread(str(folder / im["file_name"]), 0)))

    for im, r in zip(coco["images"], drawn):
        assert (grey(d, im) > grey(p, im)) == (r["gain_db"] > 12.0), (r, grey(d, im), grey(p, im))


def test_cli_spec_refusals(tmp_path, capsys):
    code, err = run_cli(["dataset", "--spec", "no_such_spec", "--n", "2", "--out", str(tmp_path / "o")], capsys)
    assert_clean_error(code, err, "--spec no_such_spec", "marine_debris_watertank")
    code, err = run_cli(["dataset", "--spec", "fls_train.yaml", "--n", "2", "--out", str(tmp_path / "o")], capsys)
    assert_clean_error(code, err, "did you mean fls_train?")
    code, err = run_cli(["dataset", "--spec", str(tmp_path), "--n", "2", "--out", str(tmp_path / "o")], capsys)
    assert_clean_error(code, err, "is a folder")
    code, err = run_cli(["dataset", "--spec", "fls_train", "--sensor", "sss", "--n", "2", "--out",
                         str(tmp_path / "o")], capsys)
    assert_clean_error(code, err, "--spec fls_train", "--sensor")
    assert not (tmp_path / "o").exists()


@pytest.mark.slow
def test_the_watertank_spec_draws_the_real_objects_at_their_pixel_sizes(tmp_path):
    """The shipped watertank spec's median labelled box area per class is within 25 % of the
    real development split's, for the classes lying on the floor (upright bottles show their
    height along range in the real frames, which the tank geometry does not give)."""
    from tests.support import REAL_WATERTANK_DIR

    if not REAL_WATERTANK_DIR.is_dir():
        pytest.skip(f"the real development split is not at {REAL_WATERTANK_DIR} (a user's machine has none)")
    from sim.dataset.generate import generate_dataset, generation_args
    from sim.dataset.labelled_folder import load_labelled_folder

    generate_dataset(tmp_path / "syn", 160, seed=5, workers=1, progress=False,
                     **generation_args(load_spec("marine_debris_watertank")))

    def median_area(folder) -> dict[str, float]:
        f = load_labelled_folder(folder)
        cats = {c["id"]: c["name"] for c in f.coco["categories"]}
        areas: dict[str, list[float]] = {}
        for a in f.coco["annotations"]:
            areas.setdefault(cats[a["category_id"]], []).append(a["bbox"][2] * a["bbox"][3])
        return {c: float(np.median(v)) for c, v in areas.items()}

    real, syn = median_area(REAL_WATERTANK_DIR), median_area(tmp_path / "syn")
    lying = [c for c in real if c not in ("Wall", "Standing-bottle", "Shampoo-bottle")]
    assert len(lying) == 8
    ratios = {c: syn[c] / real[c] for c in lying}
    assert all(0.75 <= r <= 1.25 for r in ratios.values()), ratios


def test_randomize_reads_a_nested_formation_block_as_its_dotted_keys(tmp_path):
    path = tmp_path / "spec.yaml"
    path.write_text(TANK_SPEC.replace("settings: {gain_db: 12.0}", "settings: {gain_db: 12.0}\n  randomize: "
                                      "{formation: {texture_sigma: [0.2, 1.0]}, gain_db: [10, 14]}"))
    spec = load_spec(path)
    assert spec.sonar.randomize == {"formation.texture_sigma": (0.2, 1.0), "gain_db": (10.0, 14.0)}
    drawn = spec.sonar.draw(np.random.default_rng(0))
    fields = spec.sonar.fls_fields(drawn)
    assert fields["formation"]["texture_sigma"] == drawn["formation.texture_sigma"] and fields["gain_db"] == drawn["gain_db"]
