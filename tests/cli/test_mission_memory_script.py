"""scripts/mission_memory.py: the growth fit against an analytic line, and bad input refused
in one line before any run."""

from __future__ import annotations

import numpy as np
import pytest

from tests.cli.test_study_scripts_bad_input import _refused, _script


def test_fit_growth_recovers_a_known_line():
    mod = _script("mission_memory")
    t = np.linspace(0.0, 9000.0, 400)
    rss = 300.0 + 5.0 * t / 3600.0 + np.where(t < 600.0, -80.0, 0.0)  # 5 MB/h after a 600 s warm-up
    rss = rss + np.random.default_rng(0).normal(0.0, 0.5, t.size)
    fit = mod.fit_growth(t, rss, 600.0)
    assert fit["slope_mb_per_h"] == pytest.approx(5.0, abs=0.1)
    assert fit["rss_24h_mb"] == pytest.approx(300.0 + 5.0 * 24.0, abs=1.5)
    assert fit["n_samples"] == int(np.sum(t >= 600.0))
    with pytest.raises(ValueError, match="samples after"):
        mod.fit_growth(t[:10], rss[:10], 600.0)


@pytest.mark.parametrize("argv,culprits", [
    (["--out", "{new}", "--duration-s", "0"], ("--duration-s", "> 0")),
    (["--out", "{new}", "--warmup-s", "-1"], ("--warmup-s", ">= 0")),
    (["--out", "{file}"], ("--out", "exists")),
    (["cssn_lawnmowr", "--out", "{new}"], ("cssn_lawnmowr",)),
    (["--out", "{new}", "--set", "autonomy.guidance.survey.lenght_m=70"], ("lenght_m",)),
])
def test_mission_memory_refuses(argv, culprits, capsys, tmp_path):
    (tmp_path / "f.txt").write_text("keep")
    argv = [a.format(file=tmp_path / "f.txt", new=tmp_path / "new") for a in argv]
    _refused(_script("mission_memory"), argv, capsys, *culprits)
    assert (tmp_path / "f.txt").read_text() == "keep" and not (tmp_path / "new").exists()
