"""The realism report on the real ARIS 3000 frames (``../shared/data/marine-debris-watertank-dev``
next to the repository, or ``AUVSIM_REAL_FLS_DIR``): skipped, saying so, where they are absent
(a user's machine has none). The frames are read from their folder, never copied."""


import numpy as np
import pytest

from tests.support import REAL_WATERTANK_DIR as REAL_DIR

pytestmark = pytest.mark.skipif(not (REAL_DIR / "images").is_dir(),
                                reason=f"real ARIS frames not found at {REAL_DIR} (set AUVSIM_REAL_FLS_DIR)")


def test_real_fan_outline_is_the_aris_fan():
    from sim.dataset.real_frames import fit_fan_outline, load_real_frames

    real = load_real_frames(REAL_DIR, limit=120)
    fit = fit_fan_outline(real.images)
    assert np.degrees(fit.half_angle_rad) == pytest.approx(15.0, abs=0.2)  # the ARIS 3000's 30 deg
    assert fit.edge_rms_px < 1.0
    assert abs(fit.apex_x_px - (fit.width_px - 1) / 2) < 1.0  # apex on the centre column


@pytest.mark.slow
def test_the_tank_formation_is_closer_to_real_than_the_preset(tmp_path):
    from sim.realism.report import realism_report, report_lines, side_by_side_png

    rep = realism_report(str(REAL_DIR), n_sim=24, seed=3, limit_real=80)
    before, after = rep.formations
    assert (before.name, after.name) == ("before", "after")
    assert after.profile_corr > 0.6
    # the grey histogram: a bright tail as in the real frames (the log display's is dark)
    real_skew = rep.real.measures["bg_skewness"]
    assert real_skew > 0 and after.sim.measures["bg_skewness"] > 0 > before.sim.measures["bg_skewness"]
    bg = {f.name: min(j.accuracy for j in f.judges["background"]) for f in rep.formations}
    assert bg["after"] < bg["before"] - 0.05
    assert abs(after.sim.measures["grey_p10"] - rep.real.measures["grey_p10"]) < abs(
        before.sim.measures["grey_p10"] - rep.real.measures["grey_p10"])
    lines = report_lines(rep)
    assert any("two-sample" in line for line in lines)
    side_by_side_png(rep, tmp_path / "f.png")
    assert (tmp_path / "f.png").stat().st_size > 10_000


def test_the_development_split_holds_two_fans_and_the_report_measures_the_larger():
    from sim.dataset.real_frames import fan_groups, fit_fan_outline, load_real_frames

    real = load_real_frames(REAL_DIR)
    groups = fan_groups(real.images)
    assert [len(g) for g in groups][:2] == [367, 233]
    a, b = (fit_fan_outline(real.images[g]) for g in groups[:2])
    assert np.degrees(a.half_angle_rad) == pytest.approx(15.0, abs=0.2)  # the ARIS 3000's 30 deg, equal scales
    assert np.degrees(b.half_angle_rad) < 13.0  # the other window's export is squeezed across
