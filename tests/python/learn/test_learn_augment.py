"""Training-time augmentation (mgn.learn.augment) and the foreground Dice loss."""

from __future__ import annotations

import numpy as np
import pytest

from mgn.errors import InvalidArgumentError
from mgn.learn.augment import (
    ZOOM_PROBABILITY,
    augment_view,
    geometric,
    photometric,
    resample_window,
)
from mgn.learn.config import TrainConfig


def _ramp_view(h: int, w: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Input and targets that carry each pixel's own (row, col): a linear ramp, which bilinear
    resampling reproduces exactly, so the input tells where an output pixel was sampled."""
    rows, cols = np.mgrid[0:h, 0:w].astype(np.float32)
    x = np.stack([rows, cols, rows + cols])
    t = np.stack([rows, cols])
    return x, t, cols.copy()


def _disc_view(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rows, cols = np.mgrid[0:n, 0:n] + 0.5
    mask = ((rows - 0.3 * n) ** 2 + (cols - 0.6 * n) ** 2 < (0.2 * n) ** 2).astype(np.float32)
    x = np.stack([mask, 0.5 * mask + 0.2, 1.0 - mask])
    t = np.stack([mask, mask * 0.5])
    return x, t, mask.copy()


@pytest.mark.parametrize("shape", [(48, 48), (32, 64)])
def test_geometric_augmentation_keeps_input_and_labels_aligned(shape: tuple[int, int]):
    """Zoom windows, 90-degree turns and flips move input and labels alike: the input's ramp
    (bilinear) and the targets' ramp (nearest) name the same source pixel within half a pixel
    plus the bilinear clamp at the border, and the weight follows the targets exactly."""
    x0, t0, w0 = _ramp_view(*shape)
    zoomed = turned = 0
    for seed in range(40):
        x, t, w = geometric(x0, t0, w0, np.random.default_rng(seed))
        assert x.shape == x0.shape
        assert t.shape == t0.shape
        assert w.shape == w0.shape
        # nearest picks floor(s), bilinear gives s - 0.5: they differ by at most 0.5 px, or
        # 1 px where the bilinear coordinate is clamped to the first or last pixel centre.
        assert np.abs(x[0] - t[0]).max() <= 1.0 + 1e-4
        assert np.abs(x[1] - t[1]).max() <= 1.0 + 1e-4
        interior = (t[0] > 0) & (t[0] < shape[0] - 1) & (t[1] > 0) & (t[1] < shape[1] - 1)
        assert np.abs(x[0] - t[0])[interior].max() <= 0.5 + 1e-4
        np.testing.assert_array_equal(w, t[1])
        # the source pixels seen are a contiguous block: rows/cols of t are a permutation of a
        # window, possibly transposed (a 90-degree turn)
        src_rows = np.unique(t[0])
        zoomed += len(src_rows) < shape[0] or len(np.unique(t[1])) < shape[1]
        turned += bool(np.any(np.diff(t[0], axis=1)))
    assert zoomed >= 10
    assert turned >= 10 if shape[0] == shape[1] else turned == 0


def test_geometric_augmentation_of_a_known_mask():
    """A disc drawn into the input and the targets: after any geometric change the input's disc
    (thresholded) and the target's disc agree except on the outline, and a view without a zoom
    is an exact permutation of the pixels."""
    x0, t0, w0 = _disc_view(64)
    for seed in range(30):
        x, t, w = geometric(x0, t0, w0, np.random.default_rng(seed))
        img_mask, lab_mask = x[0] > 0.5, t[0] > 0.5
        np.testing.assert_array_equal(w > 0.5, lab_mask)
        np.testing.assert_array_equal(t[1], 0.5 * t[0])
        outline = lab_mask ^ _eroded(lab_mask)
        outline |= _eroded(~lab_mask) ^ ~lab_mask
        assert not np.any((img_mask != lab_mask) & ~outline), seed
        if np.random.default_rng(seed).random() >= ZOOM_PROBABILITY:  # no zoom: exact
            np.testing.assert_array_equal(img_mask, lab_mask)
            np.testing.assert_array_equal(np.sort(x[1].ravel()), np.sort(x0[1].ravel()))


def _eroded(m: np.ndarray) -> np.ndarray:
    from scipy import ndimage

    return ndimage.binary_erosion(m, border_value=1)


def test_resample_window_by_hand():
    a = np.arange(16, dtype=np.float32).reshape(4, 4)
    # the whole image: unchanged either way
    np.testing.assert_array_equal(resample_window(a, 0, 0, 4, 4, nearest=True), a)
    np.testing.assert_allclose(resample_window(a, 0, 0, 4, 4, nearest=False), a)
    # the top-left 2 x 2 window doubled: nearest repeats each pixel twice
    near = resample_window(a, 0, 0, 2, 2, nearest=True)
    np.testing.assert_array_equal(near, [[0, 0, 1, 1], [0, 0, 1, 1], [4, 4, 5, 5], [4, 4, 5, 5]])
    # bilinear: output centres at source 0.25, 0.75, 1.25, 1.75 -> clamped 0, 0.25, 0.75, 1.25
    lin = resample_window(a, 0, 0, 2, 2, nearest=False)
    np.testing.assert_allclose(lin[0], [0, 0.25, 0.75, 1.25], atol=1e-6)
    np.testing.assert_allclose(lin[:, 0], [0, 1, 3, 5], atol=1e-6)
    # a window reaching one pixel above the image: mirrored at the top border
    up = resample_window(a, -1, 0, 4, 4, nearest=True)
    np.testing.assert_array_equal(up[:, 0], [0, 0, 4, 8])
    # zoomed out to twice the size: sources -1, 1, 3, 5 mirrored to 1, 1, 3, 3
    out = resample_window(a, -2, -2, 8, 8, nearest=True)
    np.testing.assert_array_equal(out[:, 1], [5, 5, 13, 13])


def test_photometric_augmentation_leaves_the_labels_unchanged():
    """The full mode's targets and weight are those of its geometric part alone, whatever the
    photometric changes did to the RGB channels; the depth channel is not recoloured."""
    x0, t0, w0 = _disc_view(48)
    depth = np.linspace(-1, 1, 48 * 48, dtype=np.float32).reshape(1, 48, 48)
    changed = 0
    for seed in range(20):
        x, t, w = augment_view(x0, t0, w0, "full", "rgb", np.random.default_rng(seed))
        xg, tg, wg = geometric(x0, t0, w0, np.random.default_rng(seed))
        np.testing.assert_array_equal(t, tg)
        np.testing.assert_array_equal(w, wg)
        assert x.dtype == np.float32
        assert x.min() >= 0
        assert x.max() <= 1
        changed += not np.allclose(x, xg, atol=1e-3)
        xd, td, _ = augment_view(
            np.concatenate([x0, depth]), t0, w0, "full", "rgbd", np.random.default_rng(seed)
        )
        dg, _, _ = geometric(depth, t0, w0, np.random.default_rng(seed))
        np.testing.assert_array_equal(td, tg)
        np.testing.assert_array_equal(xd[3], dg[0])
        np.testing.assert_array_equal(xd[:3], x)
    assert changed == 20


def test_photometric_keeps_grey_grey_without_a_gain_and_is_deterministic():
    rgb = np.full((3, 16, 16), 0.5, np.float32)
    a = photometric(rgb, np.random.default_rng(3))
    b = photometric(rgb, np.random.default_rng(3))
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, photometric(rgb, np.random.default_rng(4)))
    with pytest.raises(InvalidArgumentError, match=r"\(3, H, W\)"):
        photometric(rgb[:2], np.random.default_rng(0))


def test_augment_modes_and_errors():
    x0, t0, w0 = _disc_view(32)
    x, t, w = augment_view(x0, t0, w0, "none", "rgb", np.random.default_rng(0))
    assert np.array_equal(x, x0)
    assert np.array_equal(t, t0)
    assert np.array_equal(w, w0)
    seen = set()
    for seed in range(12):
        x, t, w = augment_view(x0, t0, w0, "flips", "rgb", np.random.default_rng(seed))
        np.testing.assert_array_equal(x[0], t[0])  # the mask moves with the image, exactly
        candidates = {
            "id": t0[0],
            "h": t0[0][:, ::-1],
            "v": t0[0][::-1],
            "hv": t0[0][::-1, ::-1],
        }
        seen |= {k for k, c in candidates.items() if np.array_equal(t[0], c)}
    assert seen == {"id", "h", "v", "hv"}
    with pytest.raises(InvalidArgumentError, match="augment must be one of"):
        augment_view(x0, t0, w0, "strong", "rgb", np.random.default_rng(0))
    with pytest.raises(InvalidArgumentError, match="differ in size"):
        augment_view(x0, t0[:, :10], w0, "full", "rgb", np.random.default_rng(0))
    assert TrainConfig(augment=True).augment == "flips"
    assert TrainConfig(augment=False).augment == "none"
    assert TrainConfig().augment == "full"
    assert TrainConfig().foreground_loss == "bce+dice"
    with pytest.raises(InvalidArgumentError, match="augment must be one of"):
        TrainConfig(augment="lots")
    with pytest.raises(InvalidArgumentError, match="foreground_loss"):
        TrainConfig(foreground_loss="focal")


def test_dice_loss_by_hand():
    import torch

    from mgn.learn.training import dice_loss

    t = torch.tensor([[1.0, 1.0], [0.0, 0.0]])
    logits = torch.tensor([[0.0, 0.0], [0.0, 0.0]])  # p = 0.5 everywhere
    # 1 - (2 * 1 + 1) / (2 + 2 + 1)
    assert float(dice_loss(logits, t)) == pytest.approx(1 - 3 / 5)
    big = torch.tensor([[50.0, 50.0], [-50.0, -50.0]])
    assert float(dice_loss(big, t)) == pytest.approx(0.0, abs=1e-6)
    assert float(dice_loss(-big, t)) == pytest.approx(1 - 1 / 5, abs=1e-6)
