"""The side-scan passes the shared image formation: a pulse longer than a bin correlates its
speckle along range by the Siegert relation, the display law applies, and the forward-looking
sonar's own formation fields are refused in a side-scan config."""

import numpy as np
import pytest
from pydantic import ValidationError

from autonomy.frames import rot_from_euler
from scenarios.config.sonar_formation import SonarFormationConfig
from scenarios.config.sss import SssConfig
from sim.sensors.analytic_caster import AnalyticCaster
from sim.sensors.sonar.image_formation import pulse_kernel
from sim.sensors.sss import SssSensor

SEABED_M, SONAR_DEPTH_M = 20.0, 10.0


def _intensity(formation: SonarFormationConfig, seed: int) -> np.ndarray:
    s = SssSensor(SssConfig(formation=formation), (0.0, 0.0, 0.0), np.random.default_rng(seed))
    r = s.render(0.0, np.array([0.0, 0.0, SONAR_DEPTH_M]), rot_from_euler(0.0, 0.0, 0.0), AnalyticCaster(SEABED_M))
    return (r.intensity / np.maximum(r.mean_intensity, 1e-30)).astype(float), s


def test_pulse_longer_than_a_bin_correlates_side_scan_speckle():
    white, s = _intensity(SonarFormationConfig(), 0)
    bins_per_pulse = 3.0
    form = SonarFormationConfig(pulse_length_m=bins_per_pulse * s.bin_size_m)
    lag = []
    for seed in range(30):
        x, _ = _intensity(form, seed)
        seg = x[:, s.n_bins // 5:4 * s.n_bins // 5]  # on the bottom, where the echo dwarfs the noise
        d = seg - seg.mean()
        lag.append(np.mean(d[:, :-1] * d[:, 1:]) / d.var())
    h = pulse_kernel(bins_per_pulse).astype(float)
    siegert = (np.sum(h[:-1] * h[1:]) / np.sum(h * h)) ** 2
    assert np.mean(lag) == pytest.approx(siegert, abs=0.04)
    seg = white[:, s.n_bins // 5:4 * s.n_bins // 5]
    d = seg - seg.mean()
    assert abs(np.mean(d[:, :-1] * d[:, 1:]) / d.var()) < 0.05


def test_fls_only_fields_are_refused_for_a_side_scan():
    for bad in ({"beam_correlated_speckle": True}, {"elevation_span_beamwidths": 2.0}, {"object_tail_m": 0.1},
                {"object_tail_ratio": 0.3}, {"object_rice_k": 3.0}, {"side_lobe_floor_db": -30.0},
                {"object_back_wall_ratio": 0.3}, {"object_back_wall_repeats": 2}, {"object_specular_share": 0.5}):
        (key,) = bad
        with pytest.raises(ValidationError, match=f"formation.{key}: a forward-looking sonar field"):
            SssConfig(formation=SonarFormationConfig(**bad))
    SssConfig(formation=SonarFormationConfig(pulse_length_m=0.05, texture_sigma=0.3, display_gamma=0.5))
