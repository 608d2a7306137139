"""Image formation beyond independent speckle, against analytic results: the Siegert relation
for correlated speckle, the exponential marginal, log-normal moments, the display law, the
reverberation's range law, and the floor entering the beam where the elevation span puts it."""

import numpy as np
import pytest
from scipy import stats

from scenarios.config.fls import FlsConfig
from scenarios.config.sonar_formation import SonarFormationConfig
from sim.sensors.analytic_caster import AnalyticCaster
from sim.sensors.fls import FlsSensor
from sim.sensors.sonar.image_formation import (beam_amplitude_kernel, correlated_speckle, formation_model,
                                               lognormal_texture, pulse_kernel, to_uint8_gamma)
from sim.sensors.sonar.propagation import tvg_gain


def test_kernels_have_unit_energy_and_the_pulse_its_length():
    for L in (1.0, 2.0, 3.4, 5.0):
        k = pulse_kernel(L)
        assert np.isclose(np.sum(k.astype(float) ** 2), 1.0, atol=1e-6)
        assert len(k) == int(np.ceil(L))
        # rectangle: all taps equal but a fractional last one
        assert np.isclose(k[-1] / k[0], L - (len(k) - 1) if len(k) > 1 else 1.0, atol=1e-6)
    b = beam_amplitude_kernel(np.deg2rad(0.23), np.deg2rad(0.5), 3.0)
    assert np.isclose(np.sum(b.astype(float) ** 2), 1.0, atol=1e-6)
    assert np.argmax(b) == len(b) // 2 and np.allclose(b, b[::-1])


def _siegert_lag1(h: np.ndarray) -> float:
    """Intensity correlation coefficient at lag 1 of |h * w|^2 for complex white Gaussian w:
    the squared amplitude correlation (Siegert relation)."""
    h = h.astype(float)
    rho = np.sum(h[:-1] * h[1:]) / np.sum(h * h)
    return float(rho ** 2)


def test_correlated_speckle_is_unit_mean_exponential_with_siegert_correlation():
    rng = np.random.default_rng(3)
    rk = pulse_kernel(3.0)
    bk = beam_amplitude_kernel(np.deg2rad(0.25), np.deg2rad(0.6), 3.0)
    s = correlated_speckle((400, 1200), rng, rk, bk).astype(float)
    assert abs(s.mean() - 1.0) < 0.02
    assert abs(s.var() - 1.0) < 0.05  # exponential: variance = mean^2
    # marginal: exponential (a thinned sample, to keep the samples nearly independent)
    sub = s[::7, ::9].ravel()
    assert stats.kstest(sub, "expon").pvalue > 1e-3
    d = s - s.mean()
    lag_range = float(np.mean(d[:, :-1] * d[:, 1:]) / d.var())
    lag_beam = float(np.mean(d[:-1] * d[1:]) / d.var())
    assert lag_range == pytest.approx(_siegert_lag1(rk), abs=0.02)
    assert lag_beam == pytest.approx(_siegert_lag1(bk), abs=0.02)
    # one tap each: independent samples
    w = correlated_speckle((300, 300), rng, pulse_kernel(1.0), np.ones(1, np.float32)).astype(float)
    dw = w - w.mean()
    assert abs(np.mean(dw[:, :-1] * dw[:, 1:]) / dw.var()) < 0.02


def test_lognormal_texture_moments_and_correlation_length():
    rng = np.random.default_rng(1)
    t = lognormal_texture((500, 800), rng, 0.6, 4.0, 2.0).astype(float)
    assert abs(t.mean() - 1.0) < 0.03
    lt = np.log(t)
    assert abs(lt.std() - 0.6) < 0.03
    # Gaussian-smoothed white noise: lag-1 correlation exp(-1 / (4 sigma^2)) along each axis
    z = lt - lt.mean()
    r_bins = float(np.mean(z[:, :-1] * z[:, 1:]) / z.var())
    r_lines = float(np.mean(z[:-1] * z[1:]) / z.var())
    assert r_bins == pytest.approx(np.exp(-1 / (4 * 4.0 ** 2)), abs=0.02)
    assert r_lines == pytest.approx(np.exp(-1 / (4 * 2.0 ** 2)), abs=0.03)


def test_gamma_display_law():
    inten = np.array([[1e-6, 1e-3, 0.01, 0.1, 0.5, 1.0, 4.0]], dtype=np.float32)
    g = np.full(inten.shape[1], 2.0, dtype=np.float32)
    out = to_uint8_gamma(inten, g, -3.0, 0.5)
    y = (inten.astype(float) * 2.0 * 10 ** (-0.3)) ** 0.25
    assert np.array_equal(out, np.clip(np.round(255 * y), 0, 255).astype(np.uint8))
    soft = to_uint8_gamma(inten, g, -3.0, 0.5, soft_limit=True)
    assert np.array_equal(soft, np.clip(np.round(255 * np.tanh(y)), 0, 255).astype(np.uint8))
    assert soft.max() < 255 and np.all(np.diff(soft.astype(int)) >= 0)


def test_default_formation_is_none_and_reverberation_is_flat_under_20_log_tvg():
    bins = np.linspace(0.7, 5.0, 400)
    assert formation_model(SonarFormationConfig(), bins, 0.01, 0.004, 0.004, 0.9, 3.0) is None
    f = formation_model(SonarFormationConfig(reverberation_db=-40.0), bins, 0.01, 0.004, 0.004, 0.9, 3.0)
    shown = f.reverberation * tvg_gain(bins, 20.0, 0.9)
    assert np.allclose(shown, 1e-4, rtol=1e-5)


def _floor_sonar(span: float) -> tuple[FlsSensor, float]:
    tilt = 12.0
    cfg = FlsConfig(preset="aris3000", tilt_deg=tilt, range_window_m=(0.7, 3.0), rate_hz=1.0, noise_floor_db=-200.0,
                    formation=SonarFormationConfig(elevation_span_beamwidths=span))
    return FlsSensor(cfg, rng=np.random.default_rng(0)), tilt


@pytest.mark.parametrize("span", [1.0, 2.26])
def test_floor_enters_the_beam_at_the_span_edge(span):
    """A level sonar 0.35 m above a flat floor: the first lit range is h / sin(tilt + span vbw / 2)."""
    sensor, tilt = _floor_sonar(span)
    h = 0.35
    caster = AnalyticCaster(seabed_depth_m=3.0)
    r = sensor.render(0.0, np.array([0.0, 0.0, 3.0 - h]), np.eye(3), caster, noise=False, truth=False)
    centre = r.mean_intensity[sensor.geometry.n_beams // 2]
    lit = np.flatnonzero(centre > 0)
    first_m = sensor.geometry.bin_centres_m()[lit[0]]
    expect = h / np.sin(np.deg2rad(tilt + 0.5 * 14.0 * span))
    assert first_m == pytest.approx(expect, abs=2 * sensor.geometry.range_resolution_m)


def test_formed_frames_are_seeded_and_differ_from_plain_speckle():
    cfg = dict(preset="aris3000", tilt_deg=15.0, range_window_m=(0.7, 3.0), rate_hz=1.0)
    form = SonarFormationConfig(pulse_length_m=0.009, beam_correlated_speckle=True, texture_sigma=0.5,
                                reverberation_db=-60.0, display_gamma=0.5, display_soft_limit=True)
    caster = AnalyticCaster(seabed_depth_m=3.0)
    pos = np.array([0.0, 0.0, 2.6])

    def frame(formation, seed):
        s = FlsSensor(FlsConfig(**cfg, formation=formation), rng=np.random.default_rng(seed))
        return s.render(0.0, pos, np.eye(3), caster, truth=False).frame.polar

    a, b = frame(form, 5), frame(form, 5)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, frame(form, 6))
    assert not np.array_equal(a, frame(SonarFormationConfig(), 5))


def test_object_tail_is_a_geometric_echo_train_of_the_given_energy():
    from sim.sensors.sonar.image_formation import object_tail

    x = np.zeros((2, 400), dtype=np.float32)
    x[0, 10] = 2.0
    tail = object_tail(x, 0.9, 0.3).astype(float)
    assert np.all(tail[0, :11] == 0.0) and np.all(tail[1] == 0.0)  # causal, per line
    assert tail[0, 11] == pytest.approx(2.0 * 0.3 * 0.1)
    assert np.allclose(tail[0, 12:40] / tail[0, 11:39], 0.9, rtol=1e-5)
    assert tail[0].sum() == pytest.approx(2.0 * 0.3, rel=1e-4)


@pytest.mark.parametrize("rice_k", [0.0, 1.0, 10.0])
def test_rician_speckle_moments(rice_k):
    from sim.sensors.sonar.image_formation import rician_speckle, speckle_field

    re, im = speckle_field((600, 600), np.random.default_rng(8), np.ones(1, np.float32), np.ones(1, np.float32))
    s = rician_speckle(re, im, rice_k).astype(float)
    assert s.mean() == pytest.approx(1.0, abs=0.01)
    # unit-mean Rician intensity: variance 1 - (K / (1 + K))^2
    assert s.var() == pytest.approx(1.0 - (rice_k / (1.0 + rice_k)) ** 2, rel=0.04)


def test_box_muller_pairs_are_independent_standard_normals():
    from sim.sensors.sonar.image_formation import standard_normal_pair_f32

    x, y = standard_normal_pair_f32(np.random.default_rng(1), (500, 400))
    assert x.dtype == y.dtype == np.float32
    for v in (x.ravel(), y.ravel()):
        assert stats.kstest(v, "norm").pvalue > 1e-3
    assert abs(np.corrcoef(x.ravel(), y.ravel())[0, 1]) < 0.01


def test_range_psf_spreads_an_echo_over_the_pulse_behind_it():
    """An echo in one bin is received over the pulse's length from that bin outwards, its
    energy kept (the pulse's power envelope, unit sum)."""
    from sim.sensors.sonar.echo_chain import EchoChain

    bins = 0.7 + 0.003 * (np.arange(200) + 0.5)
    form = formation_model(SonarFormationConfig(pulse_length_m=0.0105), bins, 0.003, 0.004, 0.004, 0.0, 3.0)
    chain = EchoChain(bins, 0.0, 20.0, 0.0, -200.0, "rayleigh", 2.0, 0.0, 50.0, formation=form)
    lines = np.zeros((3, 200), dtype=np.float32)
    lines[1, 50] = 1.0
    out = chain.mean_intensity(lines.copy()).astype(float)
    expect_total = chain.bin_gain[50]
    row = out[1] / expect_total
    assert np.flatnonzero(row > 1e-9).tolist() == [50, 51, 52, 53]  # 3.5 bins: four taps, from the echo out
    assert row.sum() == pytest.approx(1.0, rel=1e-5)
    k = pulse_kernel(3.5).astype(float) ** 2
    assert np.allclose(row[50:54], k / k.sum(), rtol=1e-5)


def _box_world(depth_m: float):
    """A box ``depth_m`` deep along north, its near face 1.9 m north of the origin, its base at
    2 m depth and its centre at 1.85 m (targets rest on their position), alone above a floor at
    20 m (out of the window), in a compiled MuJoCo scene."""
    from scenarios.config.world import SeabedConfig, TargetConfig, WorldConfig
    from scenarios.schema import Scenario
    from sim.scene.world import build_world
    from sim.sensors.raycast import MujocoRayCaster

    box = TargetConfig(name="box", shape="box", pos_ned=(1.9 + 0.5 * depth_m, 0.0, 2.0), rpy_deg=(0.0, 0.0, 0.0),
                       size_m=(depth_m, 0.3, 0.3), reflectivity=0.9, class_name="Box", is_target=True)
    sc = Scenario(name="box", seed=0, world=WorldConfig(seabed=SeabedConfig(kind="plane", depth_m=20.0,
                                                                             reflectivity=0.3, extent_m=40.0),
                                                         targets=(box,)))
    w = build_world(sc, with_vehicle=False)
    return w, MujocoRayCaster(w.model, w.data, w.geom_object_id, w.geom_reflectivity, exclude_body_id=-1)


def test_exit_distances_find_the_far_wall_of_the_object_alone():
    world, caster = _box_world(0.25)
    dirs = np.array([[1.0, 0.0, 0.0], [1.0, 0.05, 0.0], [0.0, 1.0, 0.0]])
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    start = np.array([1.9, 0.0, 1.85])  # on the near face
    box_id = int(world.objects[0].id)
    d = caster.exit_distances(np.repeat(start[None], 3, axis=0), dirs, np.full(3, box_id))
    assert d[0] == pytest.approx(0.25, abs=1e-6)  # the far wall along north
    assert d[1] == pytest.approx(0.25 / dirs[1, 0], abs=1e-6)
    assert d[2] == pytest.approx(0.15, abs=1e-6)  # the side wall, 0.15 m east
    up = caster.exit_distances(np.array([[0.0, 0.0, 1.85]]), np.array([[0.0, 0.0, -1.0]]), np.array([box_id]))
    assert np.isinf(up[0])  # a ray that never meets the box
    # the geoms' groups are restored: a plain cast still sees the box
    assert caster.cast(np.array([0.0, 0.0, 1.85]), dirs, 5.0).object_id[0] == box_id


@pytest.mark.parametrize("depth_m", [0.12, 0.3])
def test_back_wall_echo_lies_one_crossing_behind_the_near_wall_with_its_share_of_energy(depth_m):
    """A box face-on: its far wall's echo appears ``depth_m`` behind the near wall's (the
    rays through the middle of the face), with ``ratio`` of its energy (before the range gain,
    within what the edge rays' shorter crossings move), and the object's label covers it."""
    world, caster = _box_world(depth_m)
    ratio = 0.4

    def sensor(form):
        cfg = FlsConfig(preset="aris3000", tilt_deg=0.0, range_window_m=(0.7, 3.0), rate_hz=1.0,
                        noise_floor_db=-200.0, formation=form)
        return FlsSensor(cfg, rng=np.random.default_rng(0))

    # pulse_length_m set (one bin) only so the formation model is on in both
    plain, walled = (sensor(SonarFormationConfig(pulse_length_m=0.003, object_back_wall_ratio=r))
                     for r in (0.0, ratio))
    pos, rot = np.array([0.0, 0.0, 1.85]), np.eye(3)
    a = plain.echo_at(0.0, pos, rot, caster, world.objects, truth=True)
    b = walled.echo_at(0.0, pos, rot, caster, world.objects, truth=True)
    g = walled.geometry
    gain = walled.echo._bin_gain32.astype(float)
    centre = g.n_beams // 2
    near = a.mean_intensity[centre].astype(float) / gain
    added = (b.mean_intensity[centre].astype(float) - a.mean_intensity[centre].astype(float)) / gain
    bins = g.bin_centres_m()
    assert bins[np.argmax(near)] == pytest.approx(1.9, abs=2 * g.range_resolution_m)
    assert bins[np.argmax(added)] == pytest.approx(1.9 + depth_m, abs=2 * g.range_resolution_m)
    # nothing before the near wall; rays entering near an edge leave through the top or bottom
    # face, so some far-wall echoes lie between the two walls
    assert np.all(added[bins < 1.9 - 2 * g.range_resolution_m] <= 1e-9 * near.max())
    assert np.all(added[bins > 1.9 + depth_m + 2 * g.range_resolution_m] <= 1e-9 * near.max())
    # energy per bin carries r0 r1 of its interval (echo_lines): undo it for the ratio
    assert added.sum() * (1.9 / (1.9 + depth_m)) ** 2 == pytest.approx(ratio * near.sum(), rel=0.08)
    k_far = int(np.argmin(np.abs(bins - (1.9 + depth_m))))
    box_id = int(world.objects[0].id)
    assert b.truth.mask_polar[centre, k_far] == box_id and a.truth.mask_polar[centre, k_far] != box_id


def test_specular_share_reweights_object_rays_only():
    from types import SimpleNamespace

    from sim.sensors.sonar.image_formation import specular_objects

    cos = np.array([1.0, 0.5, 0.5, 0.0])
    dirs = np.tile([1.0, 0.0, 0.0], (4, 1))
    normal = np.stack([cos, np.sqrt(1.0 - cos ** 2), np.zeros(4)], axis=1)
    rays = SimpleNamespace(dirs=dirs, normal=normal, obj=np.array([3, 3, -1, 3]))
    s = np.array([1.0, 0.5 ** 2, 0.5 ** 2, 0.0])  # cos^2 (Lambert) strengths
    out = specular_objects(s, rays, 2.0, 0.8, 10.0)
    assert out[0] == pytest.approx(1.0)  # normal incidence: the lobe's peak equals the diffuse one
    assert out[1] == pytest.approx(0.2 * 0.5 ** 2 + 0.8 * 0.5 ** 10)
    assert out[2] == s[2]  # the floor keeps its diffuse law
    assert out[3] == 0.0


def test_back_wall_echoes_skip_objects_larger_than_a_shell_and_repeats_must_be_an_integer():
    """A box of 2.4 m (bounding radius above 1 m: a wall) gets no far-wall echo; the repeats
    key takes integers only (a bool or a string is refused, not coerced)."""
    from pydantic import ValidationError

    from scenarios.config.world import SeabedConfig, TargetConfig, WorldConfig
    from scenarios.schema import Scenario
    from sim.scene.world import build_world
    from sim.sensors.raycast import MujocoRayCaster

    wall = TargetConfig(name="wall", shape="box", pos_ned=(2.05, 0.0, 2.0), rpy_deg=(0.0, 0.0, 0.0),
                        size_m=(0.3, 2.4, 0.3), reflectivity=0.9, class_name="Wall", is_target=False)
    w = build_world(Scenario(name="w", seed=0, world=WorldConfig(
        seabed=SeabedConfig(kind="plane", depth_m=20.0, reflectivity=0.3, extent_m=40.0), targets=(wall,))),
        with_vehicle=False)
    caster = MujocoRayCaster(w.model, w.data, w.geom_object_id, w.geom_reflectivity, exclude_body_id=-1)

    def mean(ratio):
        cfg = FlsConfig(preset="aris3000", tilt_deg=0.0, range_window_m=(0.7, 3.0), rate_hz=1.0,
                        noise_floor_db=-200.0,
                        formation=SonarFormationConfig(pulse_length_m=0.003, object_back_wall_ratio=ratio))
        s = FlsSensor(cfg, rng=np.random.default_rng(0))
        return s.echo_at(0.0, np.array([0.0, 0.0, 1.85]), np.eye(3), caster, w.objects).mean_intensity

    plain, walled = mean(0.0), mean(0.5)
    assert plain.max() > 0 and np.array_equal(plain, walled)
    for bad in (True, "2", 1.5):
        with pytest.raises(ValidationError):
            SonarFormationConfig(object_back_wall_repeats=bad)
    assert SonarFormationConfig(object_back_wall_repeats=3).object_back_wall_repeats == 3
