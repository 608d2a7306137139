"""A forward-looking sonar's preset and fan size against the CNN model trained on another, and
the choice of the sonar perception reads: refused at load with one line naming the keys and
what would work (``auvsim validate`` too), or run when the scenario says so explicitly; a
preset brings its own defaults; every sonar's frames are counted in ``metrics.json``."""

from __future__ import annotations

import json

import numpy as np
import pytest

from scenarios.load import load_scenario
from sim.cli import main
from tests.support import assert_clean_error, run_cli

#: The issue's command: the three coupled overrides a preset change needed.
ARIS_LF = ["--set", "sensors.fls.preset=aris3000_lf", "--set", "sensors.fls.range_window_m=[1,15]",
           "--set", "sensors.fls.azimuth_columns=128"]
TWO_SONARS = ["--set", "sensors.fls_down.kind=fls", "--set", "sensors.fls_down.tilt_deg=30"]


@pytest.mark.parametrize("overrides,key,fix", [
    (ARIS_LF, "sensors.fls.preset", "set preset: m900_130"),
    (["--set", "sensors.fls.preset=aris3000_lf"], "sensors.fls.preset", "set preset: m900_130"),
    (["--set", "sensors.fls.fan_size_px=[600,300]"], "sensors.fls.fan_size_px", "set fan_size_px: [894, 477]"),
])
def test_a_fan_the_cnn_was_not_trained_on_is_refused_at_load(capsys, overrides, key, fix):
    code, err = run_cli(["validate", "cssn_lawnmower", *overrides], capsys)
    assert_clean_error(code, err, key, fix, "894 x 477", "autonomy.atr.accept_any_fan_size: true",
                        "autonomy.atr.detector: classical or none", "autonomy.atr.model_path", "(from --set")
    assert len(err.strip().splitlines()) == 1, err


def test_run_refuses_it_before_creating_anything(tmp_path, capsys):
    code, err = run_cli(["run", "cssn_lawnmower", "--out", str(tmp_path / "r"), "--no-rerun", "--quiet",
                      "--set", "duration_s=2", *ARIS_LF], capsys)
    assert_clean_error(code, err, "sensors.fls.preset")
    assert "internal error" not in err and not (tmp_path / "r").exists()


def test_other_detectors_and_the_explicit_option_take_the_fan(capsys):
    for extra in ("autonomy.atr.detector=classical", "autonomy.atr.detector=none",
                  "autonomy.atr.accept_any_fan_size=true"):
        assert main(["validate", "cssn_lawnmower", *ARIS_LF, "--set", extra]) == 0, capsys.readouterr().err


def test_the_cnn_runs_on_a_fan_it_was_not_trained_on_only_when_told(tmp_path):
    out = tmp_path / "r"
    assert main(["run", "cssn_lawnmower", "--out", str(out), "--no-rerun", "--quiet", "--set", "duration_s=2",
                 *ARIS_LF, "--set", "autonomy.atr.accept_any_fan_size=true"]) == 0
    per = json.loads((out / "metrics.json").read_text())["perception"]
    assert per["detector"] == "cnn" and per["sonar"] == "fls"
    assert per["sonar_frames"] == per["fls_frames"] == 6  # 3 Hz from t = 0, delivered 0.05 s later, by 2 s


def test_the_detector_resizes_another_fan_like_the_trained_one_when_told():
    from autonomy.atr.build import SHIPPED_MODEL_PATH
    from autonomy.atr.cnn_detector import CnnDetector
    from autonomy.messages import FlsFrame
    from autonomy.sonar_geometry import FanGeometry

    strict = CnnDetector(SHIPPED_MODEL_PATH, score_threshold=0.05)
    loose = CnnDetector(SHIPPED_MODEL_PATH, score_threshold=0.05, accept_any_fan_size=True)
    h, w = strict.fan_hw
    fan = np.full((h, w), 20, np.uint8)
    yy, xx = np.mgrid[:h, :w]
    fan[(xx - 447) ** 2 + (yy - 240) ** 2 < 8 ** 2] = 250  # a bright echo ...
    fan[(xx >= 440) & (xx <= 454) & (yy > 170) & (yy < 228)] = 0  # ... and its shadow (further, up the image)

    def frame(img):
        g = FanGeometry.fit(img.shape[1], img.shape[0], 1.0, 30.0, np.deg2rad(130.0))
        return FlsFrame(t_s=0.0, polar=np.zeros((0, 0), np.uint8), fan=img, geometry=g,
                        mount_pos_body_m=np.zeros(3), mount_rpy_rad=np.zeros(3))

    big = np.repeat(np.repeat(fan, 2, axis=0), 2, axis=1)  # the same fan at twice the pixels
    with pytest.raises(ValueError, match="expects a fan image of 477 x 894 px"):
        strict.detect(frame(big))
    ref = strict.detect(frame(fan))
    got = loose.detect(frame(big))
    assert ref and len(got) == len(ref)
    # INTER_AREA of a 2x pixel-replicated image is the original: the same boxes, in 2x pixels
    # (pixel centres at integers: x_big = 2 x + 0.5)
    np.testing.assert_allclose(got[0].box_xyxy_px, 2.0 * ref[0].box_xyxy_px + 0.5, atol=1e-3)
    assert got[0].score == pytest.approx(ref[0].score, abs=1e-5)


def test_a_preset_brings_its_own_defaults_and_an_explicit_key_still_wins():
    from scenarios.fls_presets import resolve_geometry

    notes: list[str] = []
    scn = load_scenario("cssn_lawnmower", ["sensors.fls.preset=aris3000_lf", "autonomy.atr.detector=classical"],
                        notes=notes)
    g = resolve_geometry(scn.sensors.fls)
    # ARIS 3000 1.8 MHz datasheet: 128 beams over 30 deg, 15 m; window = hardware limits, a column per beam
    assert (g.n_beams, g.azimuth_columns, g.window_far_m) == (128, 128, 15.0)
    assert np.rad2deg(g.fov_rad) == pytest.approx(30.0) and g.fan_size_px == (512, 512)
    assert scn.sensors.fls.tilt_deg == 15.0  # not a preset key: the scenario's stays
    assert len(notes) == 1 and "range_window_m, azimuth_columns" in notes[0] and "m900_130" in notes[0]
    assert notes[0].startswith("--set sensors.fls.preset=aris3000_lf")
    scn = load_scenario("cssn_lawnmower", ["sensors.fls.preset=aris3000_lf", "sensors.fls.range_window_m=[1,10]",
                                           "autonomy.atr.detector=classical"])
    g = resolve_geometry(scn.sensors.fls)
    assert (g.window_near_m, g.window_far_m, g.azimuth_columns) == (1.0, 10.0, 128)
    # the file's own preset, or the same preset set again: the file's keys stand
    for over in ([], ["sensors.fls.preset=m900_130"]):
        notes = []
        scn = load_scenario("cssn_lawnmower", over, notes=notes)
        assert scn.sensors.fls.range_window_m == (1.0, 30.0) and scn.sensors.fls.azimuth_columns == 361
        assert notes == []
    scn = load_scenario("track_static_vehicle")  # an ARIS preset set in the file with its window
    assert scn.sensors.fls.range_window_m == (1.0, 15.0)


def test_validate_says_which_keys_the_preset_replaced(capsys):
    assert main(["validate", "cssn_lawnmower", "--set", "sensors.fls.preset=aris3000_lf",
                 "--set", "autonomy.atr.detector=classical"]) == 0
    captured = capsys.readouterr()
    assert "auvsim validate: note: --set sensors.fls.preset=aris3000_lf: sensors.fls takes the aris3000_lf " \
           "preset's range_window_m, azimuth_columns" in captured.err
    assert "range_window_m: null" in captured.out


@pytest.mark.parametrize("value,why", [("gps", "is a gps sensor"), ("fls2", "is not an enabled sensor")])
def test_the_atr_sonar_must_be_an_enabled_fls(capsys, value, why):
    code, err = run_cli(["validate", "cssn_lawnmower", *TWO_SONARS, "--set", f"autonomy.atr.sonar_sensor={value}"],
                     capsys)
    assert_clean_error(code, err, "autonomy.atr.sonar_sensor", why, "allowed: fls, fls_down")


def test_the_atr_sonar_is_checked_against_the_model_too(capsys):
    code, err = run_cli(["validate", "cssn_lawnmower", *TWO_SONARS, "--set", "sensors.fls_down.fan_size_px=[600,300]",
                      "--set", "autonomy.atr.sonar_sensor=fls_down"], capsys)
    assert_clean_error(code, err, "sensors.fls_down.fan_size_px")
    # the sonar perception does not read may make any fan
    assert main(["validate", "cssn_lawnmower", *TWO_SONARS, "--set", "sensors.fls_down.fan_size_px=[600,300]"]) == 0


def test_metrics_count_each_sonars_frames_and_name_the_one_perception_read(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["run", "cssn_lawnmower", "--out", str(out), "--no-rerun", "--quiet", "--detector", "none",
                 "--set", "duration_s=4", *TWO_SONARS, "--set", "sensors.fls_down.rate_hz=2"]) == 0
    stdout = capsys.readouterr().out
    per = json.loads((out / "metrics.json").read_text())["perception"]
    # frames at k / rate_hz (k = 0, 1, ...), delivered 0.05 s later, by 4 s: floor(3.95 rate_hz) + 1
    assert per["fls_frames_by_sensor"] == {"fls": 12, "fls_down": 8} and per["fls_frames"] == 20
    assert per["sonar"] == "fls" and per["sonar_frames"] == 12
    assert "sensors.fls_down rendered and recorded, not processed" in per["note"]
    assert "sonar frames: fls 12, fls_down 8; perception read sensors.fls;" in stdout


def test_the_scenario_chooses_the_sonar_perception_reads():
    from sim.mission import Mission

    scn = load_scenario("cssn_lawnmower", ["duration_s=3", "sensors.fls_down.kind=fls", "sensors.fls_down.tilt_deg=30",
                                           "sensors.fls_down.range_window_m=[1,20]", "sensors.fls_down.rate_hz=2",
                                           "autonomy.atr.detector=none", "autonomy.atr.sonar_sensor=fls_down"])
    mission = Mission(scn)
    mission.reset()
    while not mission.done:
        mission.step()
    assert mission.fls.name == "fls_down" and mission.fls.geometry.window_far_m == 20.0
    assert mission.info().perception_sonar == "fls_down"
    assert mission.fls_frames_by_sensor == {"fls": 9, "fls_down": 6}  # floor(2.95 rate_hz) + 1
    assert mission.perception.n_frames == 6  # the frames of fls_down, not of fls
    assert mission.perception.fls is mission.sensors["fls_down"]
