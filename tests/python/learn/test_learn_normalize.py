"""The per-image RGB normalisation of the baselines (``ModelConfig.rgb_norm``) and the exposure
change of the training augmentation."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

import mgn
import mgn.learn.augment as augment_module
from mgn.errors import InvalidArgumentError
from mgn.learn import ModelConfig, Predictor, TrainConfig, train
from mgn.learn.augment import PHOTOMETRIC, augment_view, geometric, photometric
from mgn.learn.checkpoint import MODEL_FORMAT, read_torch_file, write_torch_file
from mgn.learn.targets import RGB_NORM_MIN_STD, model_input, normalize_rgb


def _photo(seed: int, h: int = 24, w: int = 20) -> np.ndarray:
    return np.random.default_rng(seed).uniform(0.1, 0.6, size=(3, h, w)).astype(np.float32)


def test_image_normalisation_is_standardisation_per_channel():
    x = _photo(0)
    y = normalize_rgb(x, "image")
    assert y.dtype == np.float32
    assert y.shape == x.shape
    # against the definition, computed independently per channel in float64
    for c in range(3):
        ch = x[c].astype(np.float64)
        np.testing.assert_allclose(y[c], (ch - ch.mean()) / ch.std(), rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(y.mean(axis=(1, 2)), 0.0, atol=1e-5)
    np.testing.assert_allclose(y.std(axis=(1, 2)), 1.0, atol=1e-5)
    # deterministic, and a batch is normalised image by image
    np.testing.assert_array_equal(y, normalize_rgb(x.copy(), "image"))
    batch = np.stack([x, _photo(1)])
    nb = normalize_rgb(batch, "image")
    np.testing.assert_array_equal(nb[0], y)
    np.testing.assert_array_equal(nb[1], normalize_rgb(_photo(1), "image"))
    # "none" is the identity
    np.testing.assert_array_equal(normalize_rgb(x, "none"), x)


def test_a_darker_photo_of_another_white_balance_gives_the_same_input():
    """A gain and an offset per channel (exposure, white balance, black level) change nothing."""
    x = _photo(2)
    gains = np.array([0.22, 0.18, 0.3], np.float32)[:, None, None]
    offsets = np.array([0.01, 0.0, 0.02], np.float32)[:, None, None]
    dark = x * gains + offsets
    assert dark.mean() < 0.3 * x.mean()
    np.testing.assert_allclose(
        normalize_rgb(dark, "image"), normalize_rgb(x, "image"), rtol=1e-4, atol=1e-4
    )
    assert not np.allclose(dark, x, atol=0.05)


def test_a_uniform_channel_is_not_blown_up():
    x = _photo(3)
    x[1] = 0.4
    x[2] = 0.4 + np.float32(0.001) * (np.arange(x.shape[2]) % 2)  # std 0.0005 < the floor
    y = normalize_rgb(x, "image")
    np.testing.assert_array_equal(y[1], 0.0)
    assert np.abs(y[2]).max() <= 0.0005 / RGB_NORM_MIN_STD + 1e-6


def test_model_input_normalises_rgb_and_keeps_depth():
    rgb = _photo(4)
    depth = np.linspace(-2, 2, 24 * 20, dtype=np.float32).reshape(1, 24, 20)
    x = np.concatenate([rgb, depth])
    y = model_input(x, "rgbd", "image")
    np.testing.assert_array_equal(y[:3], normalize_rgb(rgb, "image"))
    np.testing.assert_array_equal(y[3], depth[0])
    np.testing.assert_array_equal(model_input(depth, "depth", "image"), depth)
    np.testing.assert_array_equal(model_input(x, "rgbd", "none"), x)
    yb = model_input(np.stack([x, x]), "rgbd", "image")
    np.testing.assert_array_equal(yb[1], y)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: normalize_rgb(np.zeros((4, 8, 8)), "image"), r"\(3, H, W\) or \(N, 3, H, W\)"),
        (lambda: normalize_rgb(np.zeros((8, 8, 3)), "image"), r"got \(8, 8, 3\)"),
        (lambda: normalize_rgb(np.zeros((3, 8)), "image"), r"got \(3, 8\)"),
        (lambda: normalize_rgb(np.zeros((3, 8, 8)), "auto"), "rgb_norm must be one of"),
        (lambda: model_input(np.zeros((3, 8, 8)), "rgbd", "image"), "rgbd input has 4"),
        (lambda: model_input(np.zeros((4, 8, 8)), "rgb", "none"), r"got \(4, 8, 8\)"),
        (lambda: model_input(np.zeros((1, 8, 8)), "depth", "gain"), "rgb_norm must be one of"),
        (lambda: ModelConfig(rgb_norm="gain"), "rgb_norm must be one of"),
    ],
)
def test_wrong_shapes_and_names_give_clear_errors(call, match):
    with pytest.raises(InvalidArgumentError, match=match):
        call()


def test_exposure_change_reaches_dark_photographs(monkeypatch: pytest.MonkeyPatch):
    """With every other photometric change off, the exposure change multiplies the view by
    ``2 ** ev`` (clipped to [0, 1]); its range reaches views 4-8 times darker; the labels do
    not move."""
    only = {k: ((v[0][0], v[0][0]) if k == "gain" else v[0], 0.0) for k, v in PHOTOMETRIC.items()}
    only["gain"] = ((1.0, 1.0), 1.0)
    only["exposure"] = (PHOTOMETRIC["exposure"][0], 1.0)
    monkeypatch.setattr(augment_module, "PHOTOMETRIC", only)
    x = np.full((3, 8, 8), 0.5, np.float32)
    factors = []
    for seed in range(200):
        y = photometric(x, np.random.default_rng(seed))
        f = float(y.mean()) / 0.5
        np.testing.assert_allclose(y, min(0.5 * f, 1.0), atol=1e-6)  # one factor everywhere
        factors.append(f)
    lo = PHOTOMETRIC["exposure"][0][0]
    assert min(factors) < 2.0 ** (lo + 0.2)
    assert min(factors) >= 2.0**lo - 1e-6
    assert max(factors) <= 1.0 / 0.5 + 1e-6  # clipped at 1
    assert sum(f < 0.25 for f in factors) > 20


def test_the_default_augmentation_keeps_masks_aligned_and_darkens_some_views():
    n = 40
    rows, cols = np.mgrid[0:n, 0:n] + 0.5
    mask = ((rows - 12) ** 2 + (cols - 25) ** 2 < 64).astype(np.float32)
    x0 = np.stack([0.2 + 0.6 * mask, 0.3 + 0.5 * mask, 0.25 + 0.5 * mask])
    t0, w0 = mask[None].copy(), mask.copy()
    dark = 0
    for seed in range(40):
        x, t, _ = augment_view(x0, t0, w0, "full", "rgb", np.random.default_rng(seed))
        xg, tg, _ = geometric(x0, t0, w0, np.random.default_rng(seed))
        np.testing.assert_array_equal(t, tg)
        # the object is where its mask went: brighter than the bin on average, whatever the
        # exposure (the object/bin contrast survives gain, gamma and clipping at 0)
        lum = x.mean(axis=0)
        on, off = t[0] > 0.5, t[0] < 0.5
        if on.any() and off.any():
            assert lum[on].mean() > lum[off].mean()
        dark += float(x.mean()) < 0.35 * float(xg.mean())
    assert dark >= 3


def test_trained_with_image_normalisation_exposure_does_not_matter(
    small_dataset: Path, tmp_path: Path
):
    mc = ModelConfig(image_size=32, width=4, rgb_norm="image")
    res = train(
        small_dataset,
        tmp_path / "m",
        model_config=mc,
        train_config=TrainConfig(epochs=1, batch_size=3),
        views=[5],
        num_threads=1,
        progress=False,
    )
    pred = Predictor(res.model_path, num_threads=1)
    assert pred.config.rgb_norm == "image"
    rgb = mgn.Dataset(small_dataset).scene(0).view(5).rgb
    # the image at half its exposure (rounded to 8 bits again): nearly the same output
    p = pred.maps(rgb, None)[0]
    half = (rgb.astype(np.float64) * 0.5).round().astype(np.uint8)
    p_half = pred.maps(half, None)[0]
    assert np.abs(p - p_half).max() < 0.05
    # a model file of a version without rgb_norm was trained on RGB as read
    data = read_torch_file(res.model_path, MODEL_FORMAT)
    del data["model_config"]["rgb_norm"]
    write_torch_file(tmp_path / "old.pt", data)
    old = Predictor(tmp_path / "old.pt", num_threads=1)
    assert old.config.rgb_norm == "none"
    assert ModelConfig.from_dict({}).rgb_norm == ModelConfig().rgb_norm
    assert not torch.equal(
        torch.from_numpy(old.maps(rgb, None)[0]), torch.from_numpy(p)
    )  # the same weights on another input normalisation
