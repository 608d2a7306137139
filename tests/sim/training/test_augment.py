"""``train-atr --augment sonar``: the random image formation drawn per crop."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch", reason="torch not installed: training needs the `train` extra")

from sim.training import train as T  # noqa: E402


def _lag1_along(x, axis: int) -> float:
    a = x - x.mean()
    n = a.shape[axis]
    u, v = np.take(a, np.arange(n - 1), axis=axis), np.take(a, np.arange(1, n), axis=axis)
    return float((u * v).mean() / (a * a).mean())


def _formation(monkeypatch, **ranges):
    monkeypatch.setattr(T, "SONAR_FORMATION", {**T.SONAR_FORMATION, **ranges})


def test_the_blur_correlates_white_noise_as_a_gaussian_of_its_sigma(monkeypatch):
    # white noise through a Gaussian of sigma s: lag-1 correlation exp(-1 / (4 s^2))
    _formation(monkeypatch, probability=1.0, blur_sigma_px=(1.0, 1.0), speckle_sigma=(0.0, 0.0),
               noise_sigma=(0.0, 0.0), contrast=(1.0, 1.0))
    torch.manual_seed(0)
    x = torch.rand(8, 1, 96, 96)
    y = T._sonar_formation(torch, x, np.random.default_rng(0))[:, 0, 8:-8, 8:-8].numpy()
    for axis in (1, 2):
        assert _lag1_along(y, axis) == pytest.approx(np.exp(-0.25), abs=0.02)
    assert abs(_lag1_along(x.numpy()[:, 0], 1)) < 0.02


def test_the_speckle_keeps_the_mean_and_draws_the_lognormal_spread(monkeypatch):
    s = 0.4
    _formation(monkeypatch, probability=1.0, blur_sigma_px=(0.0, 0.0), speckle_sigma=(s, s),
               noise_sigma=(0.0, 0.0), contrast=(1.0, 1.0))
    torch.manual_seed(1)
    x = torch.full((4, 1, 128, 128), 0.2)
    y = T._sonar_formation(torch, x, np.random.default_rng(1)).numpy() / 0.2
    assert y.mean() == pytest.approx(1.0, abs=0.01)
    assert y.std() == pytest.approx(np.sqrt(np.exp(s * s) - 1.0), rel=0.03)


def test_a_crop_left_alone_is_unchanged_and_boxes_never_move(monkeypatch):
    _formation(monkeypatch, probability=0.0)
    x = torch.rand(3, 1, 32, 48)
    assert torch.equal(T._sonar_formation(torch, x, np.random.default_rng(0)), x)
    _formation(monkeypatch, probability=1.0)
    boxes = [np.array([[3.0, 4.0, 10.0, 12.0]]), np.zeros((0, 4)), np.array([[0.0, 0.0, 47.0, 31.0]])]
    torch.manual_seed(2)
    img, out = T._augment(torch, x.clone(), boxes, np.random.default_rng(5), 48, "sonar")
    assert img.shape == x.shape and not torch.equal(img, x)
    for b, o in zip(boxes, out):  # each box as it was, or mirrored with its crop
        mirrored = b.copy()
        mirrored[:, [0, 2]] = 47 - b[:, [2, 0]]
        assert np.array_equal(o, b) or np.array_equal(o, mirrored)


def test_the_same_generators_draw_the_same_formation():
    x = torch.rand(4, 1, 40, 40)
    out = []
    for _ in range(2):
        torch.manual_seed(3)
        out.append(T._sonar_formation(torch, x, np.random.default_rng(3)))
    assert torch.equal(out[0], out[1])


def test_an_unknown_augmentation_is_refused(tmp_path):
    with pytest.raises(ValueError, match="augment 'strong': expected one of basic, sonar"):
        T.train_atr(tmp_path, tmp_path / "x.onnx", T.TrainParams(augment="strong"), log=lambda *_: None)
