"""The realism report's parts on cases with known answers: a fan drawn from a known geometry,
speckle of known correlation, two-sample judges on equal and on different sets, the folder
reader's errors and the command's one-line refusals."""

from pathlib import Path

import cv2
import numpy as np
import pytest

from autonomy.sonar_geometry import FanGeometry
from sim.realism.image_measures import FrameSetMeasures, _fwhm
from sim.dataset.real_frames import RealDataError, fan_groups, fit_fan_outline, load_real_frames
from sim.realism.two_sample import PATCH_FEATURES, balanced_sets, feature_judges, patch_features
from tests.support import assert_clean_error, run_cli

GEOM = FanGeometry(320, 480, 0.7, 2.9, np.deg2rad(30.0), 0.0050, 159.4, 602.5)


def _fan_images(geom: FanGeometry, n: int, rng: np.random.Generator, corr_px: float = 0.0) -> np.ndarray:
    yy, xx = np.mgrid[0:geom.height_px, 0:geom.width_px]
    r, a = geom.pixel_to_polar(xx, yy)
    inside = geom.inside(r, a)
    out = []
    for _ in range(n):
        img = rng.exponential(30.0, (geom.height_px, geom.width_px)).astype(np.float32)
        if corr_px > 0:
            img = cv2.GaussianBlur(img, (0, 0), corr_px)
        out.append(np.where(inside, np.clip(img + 1, 1, 255), 0).astype(np.uint8))
    return np.stack(out)


def test_fan_outline_recovers_a_known_geometry():
    imgs = _fan_images(GEOM, 5, np.random.default_rng(0))
    fit = fit_fan_outline(imgs)
    assert fit.apex_x_px == pytest.approx(GEOM.apex_x_px, abs=0.5)
    assert fit.apex_y_px == pytest.approx(GEOM.apex_y_px, abs=2.0)
    assert np.degrees(fit.half_angle_rad) == pytest.approx(15.0, abs=0.1)
    assert fit.far_px == pytest.approx(2.9 / 0.005, abs=1.0)
    assert fit.near_px == pytest.approx(0.7 / 0.005, abs=1.5)
    g = fit.geometry(0.7)
    assert g.range_max_m == pytest.approx(2.9, rel=0.01)
    assert g.m_per_px == pytest.approx(0.005, rel=0.01)


def test_fwhm_of_known_autocorrelations():
    assert _fwhm(np.array([1.0, 0.0, 0.0])) == pytest.approx(1.0)  # white: half-height at lag 1/2
    lags = np.arange(10)
    sigma = 3.0  # Gaussian ACF exp(-k^2 / (2 s^2)): FWHM 2 s sqrt(2 ln 2), up to linear interpolation
    est = _fwhm(np.exp(-lags ** 2 / (2 * sigma ** 2)))
    assert est == pytest.approx(2 * sigma * np.sqrt(2 * np.log(2)), rel=0.03)


def test_speckle_measures_see_correlation():
    rng = np.random.default_rng(2)
    white = FrameSetMeasures(GEOM, 128)
    smooth = FrameSetMeasures(GEOM, 128)
    masks = np.zeros((GEOM.height_px, GEOM.width_px), np.uint8)
    for im in _fan_images(GEOM, 3, rng):
        white.add(im, masks, rng)
    for im in _fan_images(GEOM, 3, rng, corr_px=1.5):
        smooth.add(im, masks, rng)
    w, s = white.summary(), smooth.summary()
    assert abs(w["speckle_lag1_range"]) < 0.3  # white, but resampled bilinearly onto the polar grid
    assert s["speckle_lag1_range"] > 0.6
    assert s["speckle_len_range_mid"] > 2.0 * w["speckle_len_range_mid"]
    assert w["grey_p10"] == pytest.approx(-np.log(0.9), abs=0.05)  # exponential over its mean
    assert w["bg_skewness"] == pytest.approx(2.0, abs=0.4)
    prof = white.range_profile()
    assert np.allclose(prof, 1.0, atol=0.05)


def test_patch_features_and_judges():
    rng = np.random.default_rng(4)
    a = [rng.exponential(60, (64, 64)) for _ in range(120)]
    b = [rng.exponential(60, (64, 64)) for _ in range(120)]
    c = [cv2.GaussianBlur(rng.exponential(60, (64, 64)).astype(np.float32), (0, 0), 1.0) for _ in range(120)]
    fa, fb, fc = (np.array([patch_features(p) for p in s]) for s in (a, b, c))
    assert fa.shape == (120, len(PATCH_FEATURES)) == (120, 30)
    groups = np.arange(120) // 4
    X, y, g = balanced_sets(fa, groups, fb, groups, rng)
    same = feature_judges(X, y, g)
    assert all(0.35 < j.accuracy < 0.65 for j in same), same
    X, y, g = balanced_sets(fa, groups, fc, groups, rng)
    diff = feature_judges(X, y, g)
    assert all(j.accuracy > 0.95 for j in diff), diff


def test_reader_refuses_bad_folders(tmp_path: Path):
    with pytest.raises(RealDataError, match="no such folder"):
        load_real_frames(tmp_path / "nope")
    (tmp_path / "images").mkdir()
    with pytest.raises(RealDataError, match="no PNG"):
        load_real_frames(tmp_path)
    cv2.imwrite(str(tmp_path / "images" / "a.png"), np.zeros((48, 32), np.uint8))
    cv2.imwrite(str(tmp_path / "images" / "b.png"), np.zeros((40, 32), np.uint8))
    with pytest.raises(RealDataError, match="one size"):
        load_real_frames(tmp_path)


def test_cli_refuses_bad_input(tmp_path: Path, capsys):
    code, err = run_cli(["realism", "--real", str(tmp_path / "missing")], capsys)
    assert_clean_error(code, err, "--real", "missing")
    code, err = run_cli(["realism", "--real", str(tmp_path), "--frames", "0"], capsys)
    assert_clean_error(code, err, "--frames")
    other = tmp_path / "other"
    other.mkdir()
    (other / "keep.txt").write_text("mine")
    code, err = run_cli(["realism", "--real", str(tmp_path), "--out", str(other)], capsys)
    assert_clean_error(code, err, "--out")
    assert (other / "keep.txt").read_text() == "mine"


def test_frames_of_two_fans_are_grouped_and_each_fits_its_own():
    other = FanGeometry(320, 480, 1.5, 3.75, np.deg2rad(24.4), 0.0052, 159.5, 749.0)  # a narrower, farther fan
    rng = np.random.default_rng(1)
    imgs = np.concatenate([_fan_images(GEOM, 6, rng), _fan_images(other, 4, rng)])
    order = rng.permutation(len(imgs))
    groups = fan_groups(imgs[order])
    assert [len(g) for g in groups] == [6, 4]
    assert set(order[groups[0]]) == set(range(6))
    fit_a, fit_b = fit_fan_outline(imgs[order][groups[0]]), fit_fan_outline(imgs[order][groups[1]])
    assert np.degrees(fit_a.half_angle_rad) == pytest.approx(15.0, abs=0.1)
    assert np.degrees(fit_b.half_angle_rad) == pytest.approx(12.2, abs=0.1)
    assert fit_b.apex_y_px == pytest.approx(749.0, abs=2.0)


def test_images_without_a_fan_are_refused_in_one_line():
    rng = np.random.default_rng(0)
    noise = rng.integers(1, 255, (3, 480, 320)).astype(np.uint8)  # lit everywhere: a rectangle, not a fan
    with pytest.raises(RealDataError, match="no sonar fan found"):
        fit_fan_outline(noise)
    with pytest.raises(RealDataError, match="no sonar fan found"):
        fit_fan_outline(np.zeros((3, 480, 320), np.uint8))


def test_the_report_refuses_bad_arguments_by_name(tmp_path: Path):
    from sim.realism.report import realism_report

    for kwargs, name in (({"real_dir": 123}, "real_dir"), ({"n_sim": 0}, "n_sim"), ({"n_sim": "3"}, "n_sim"),
                         ({"seed": -1}, "seed"), ({"near_m": "0.7"}, "near_m"), ({"near_m": 0.0}, "near_m"),
                         ({"formations": "after"}, "formations"), ({"formations": ("tank",)}, "formations"),
                         ({"limit_real": 0}, "limit_real")):
        args = {"real_dir": tmp_path, **kwargs}
        with pytest.raises(ValueError, match=name):
            realism_report(args.pop("real_dir"), **args)


def _write_fan_folder(root: Path, n: int = 12, masks: bool = False) -> Path:
    (root / "images").mkdir(parents=True)
    if masks:
        (root / "masks").mkdir()
    for i, img in enumerate(_fan_images(GEOM, n, np.random.default_rng(2))):
        cv2.imwrite(str(root / "images" / f"f{i}.png"), img)
        if masks:
            cv2.imwrite(str(root / "masks" / f"f{i}.png"), np.zeros_like(img))
    return root


def test_cli_names_a_near_range_the_preset_cannot_render(tmp_path: Path, capsys):
    real = _write_fan_folder(tmp_path / "fans")
    for near in ("3", "0.01"):
        code, err = run_cli(["realism", "--real", str(real), "--near-m", near, "--frames", "2", "--quiet"], capsys)
        assert_clean_error(code, err, "--near-m", "[0.7, 1.2")


def test_cli_refuses_frames_without_a_fan(tmp_path: Path, capsys):
    (tmp_path / "noise" / "images").mkdir(parents=True)
    rng = np.random.default_rng(0)
    for i in range(3):
        cv2.imwrite(str(tmp_path / "noise" / "images" / f"n{i}.png"), rng.integers(1, 255, (48, 32)).astype(np.uint8))
    code, err = run_cli(["realism", "--real", str(tmp_path / "noise"), "--frames", "2", "--quiet"], capsys)
    assert_clean_error(code, err, "--real", "no sonar fan found")
    assert len(err.strip().splitlines()) == 1


def test_json_is_one_line_with_null_where_nothing_was_measured(tmp_path: Path, capsys):
    import json

    real = _write_fan_folder(tmp_path / "fans", n=6)  # no masks: no object measures
    capsys.readouterr()
    from sim.cli import main

    assert main(["realism", "--real", str(real), "--frames", "2", "--formation", "after", "--json"]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    data = json.loads(out[-1], parse_constant=lambda c: pytest.fail(f"bare {c} in the JSON"))
    assert data["real"]["measures"]["object_p99_bg"] is None
    assert any("no masks" in n for n in data["notes"])
    assert any("fewer than 50" in n for n in data["notes"])


def test_the_shells_formation_renders_beside_the_tank_estimate(tmp_path: Path, capsys):
    """``--formation all`` measures the three formations on the same scenes; the shells'
    settings are the tank estimate's plus the far-wall echo and the specular lobe."""
    import json

    real = _write_fan_folder(tmp_path / "fans", n=6)
    capsys.readouterr()
    from sim.cli import main

    assert main(["realism", "--real", str(real), "--frames", "2", "--formation", "all", "--json"]) == 0
    data = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert list(data["simulated"]) == ["before", "after", "shells"]
    shells = data["options"]["formation_settings"]["shells"]["formation"]
    assert shells["object_back_wall_ratio"] == 0.5 and shells["object_specular_share"] == 0.6


def test_bright_over_dim_correlation_sees_where_the_floor_is_smooth():
    """Frames drawn at two brightnesses: with one speckle correlation in both, the brighter
    patches of a range band are as correlated as the dimmer ones (about 1); when the brighter
    frames are smoother, the ratio is well above 1."""
    rng = np.random.default_rng(3)
    masks = np.zeros((GEOM.height_px, GEOM.width_px), np.uint8)
    yy, xx = np.mgrid[0:GEOM.height_px, 0:GEOM.width_px]
    r, a = GEOM.pixel_to_polar(xx, yy)
    inside = GEOM.inside(r, a)

    def frame(level: float, corr_px: float) -> np.ndarray:
        img = cv2.GaussianBlur(rng.exponential(1.0, inside.shape).astype(np.float32), (0, 0), corr_px)
        img = 1.0 + (img - img.mean()) / img.std() * 0.5  # unit mean, the same contrast at any correlation
        return np.where(inside, np.clip(level * img, 1, 255), 0).astype(np.uint8)

    same, mixed = FrameSetMeasures(GEOM, 128), FrameSetMeasures(GEOM, 128)
    for k in range(16):
        bright = k % 2 == 0
        same.add(frame(90.0 if bright else 40.0, 1.2), masks, rng, n_bg_patches=6)
        mixed.add(frame(90.0 if bright else 40.0, 2.5 if bright else 0.7), masks, rng, n_bg_patches=6)
    assert same.summary()["bright_dim_corr"] == pytest.approx(1.0, abs=0.1)
    assert mixed.summary()["bright_dim_corr"] > 1.5
