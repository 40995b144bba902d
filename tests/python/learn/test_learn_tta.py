"""Test-time augmentation of the learning baselines (``Predictor(tta=...)``, ``--tta``): the
averaged maps against the flipped and turned predictions computed by hand with torch's own
flip / rot90 on a small random network."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch
from PIL import Image

from mgn.cli.main import main
from mgn.errors import InvalidArgumentError
from mgn.learn import ModelConfig, Predictor
from mgn.learn.checkpoint import MODEL_FORMAT, write_torch_file
from mgn.learn.model import build_model
from mgn.learn.predict import DEFAULT_TTA, TTA_MODES, predict_files
from mgn.learn.real_eval import evaluate_real
from mgn.learn.targets import model_input, network_input, network_shape

# a non-square image: the network sees 16 x 32 px, the quarter turns 32 x 16 px
H, W = 30, 56
CONFIG = ModelConfig(image_size=32, width=4)


@pytest.fixture(scope="module")
def random_model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A model file of an untrained small U-Net (random weights: no symmetry of its own)."""
    torch.manual_seed(3)
    net = build_model(CONFIG)
    with torch.no_grad():
        for p in net.parameters():  # GroupNorm's affine weights start at 1 / 0: vary them
            p.add_(0.2 * torch.randn_like(p))
    path = tmp_path_factory.mktemp("tta") / "model.pt"
    write_torch_file(
        path,
        {
            "format": MODEL_FORMAT,
            "model_config": CONFIG.to_dict(),
            "training": {},
            "state_dict": {k: v.detach().clone() for k, v in net.state_dict().items()},
        },
    )
    return path


def _image(seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    rgb = rng.integers(0, 256, (H, W, 3), dtype=np.uint8)
    rgb[5:20, 8:30] = (230, 200, 40)  # an off-centre object: flips move it
    return rgb


def _by_hand(model_path: Path, rgb: np.ndarray, copies: list[tuple[int, bool]]) -> np.ndarray:
    """Mean over ``copies`` (quarter turns counter-clockwise, then a left-right mirror) of the
    network's sigmoid maps, each turned back, with torch.rot90 / torch.flip in float64."""
    p = Predictor(model_path, num_threads=1)
    x = model_input(
        network_input(rgb, None, "rgb", network_shape(H, W, CONFIG.image_size)), "rgb", "image"
    )
    t = torch.from_numpy(x)[None]
    maps = []
    with torch.no_grad():
        for k, mirror in copies:
            a = torch.rot90(t, k, dims=(2, 3))
            if mirror:
                a = torch.flip(a, dims=(3,))
            y = torch.sigmoid(p.model(a))
            if mirror:
                y = torch.flip(y, dims=(3,))
            maps.append(torch.rot90(y, -k, dims=(2, 3))[0].double())
    return torch.stack(maps).mean(0).numpy()


def test_tta_is_the_mean_of_the_turned_predictions(random_model: Path):
    rgb = _image()
    lr = [(0, False), (0, True)]  # image, left-right mirror
    ud = [(2, True)]  # a half turn then a left-right mirror: the upside-down mirror
    half = [(2, False)]
    dihedral = [(k, m) for k in range(4) for m in (False, True)]
    expected = {
        "flips": _by_hand(random_model, rgb, lr + ud),
        "flips+rot180": _by_hand(random_model, rgb, lr + ud + half),
        "dihedral": _by_hand(random_model, rgb, dihedral),
    }
    # the upside-down mirror, by hand as torch.flip of the rows
    p1 = Predictor(random_model, num_threads=1)
    x = model_input(network_input(rgb, None, "rgb", (16, 32)), "rgb", "image")
    with torch.no_grad():
        t = torch.flip(torch.from_numpy(x)[None], dims=(2,))
        up = torch.flip(torch.sigmoid(p1.model(t)), dims=(2,))[0].double().numpy()
    np.testing.assert_allclose(_by_hand(random_model, rgb, ud), up, atol=1e-6)
    single = p1.maps(rgb, None)[0]
    assert single.shape == (3, 16, 32)
    for mode, want in expected.items():
        assert len(TTA_MODES[mode]) == {"flips": 3, "flips+rot180": 4, "dihedral": 8}[mode]
        got, size = Predictor(random_model, num_threads=1, tta=mode).maps(rgb, None)
        assert size == (H, W)
        assert got.dtype == np.float32
        assert got.shape == single.shape
        np.testing.assert_allclose(got, want, rtol=0, atol=2e-6)
        # the copies see different pixels: the mean is not the plain prediction
        assert np.abs(got - single).max() > 1e-3


def test_tta_none_is_the_plain_forward_pass(random_model: Path):
    rgb = _image(1)
    plain = _by_hand(random_model, rgb, [(0, False)]).astype(np.float32)
    assert DEFAULT_TTA == "none"
    for p in (
        Predictor(random_model, num_threads=1),
        Predictor(random_model, num_threads=1, tta="none"),
        Predictor(random_model, num_threads=1, tta="dihedral").with_tta("none"),
    ):
        np.testing.assert_array_equal(p.maps(rgb, None)[0], plain)
    a = Predictor(random_model, num_threads=1).predict(rgb)
    b = Predictor(random_model, num_threads=1, tta="none").predict(rgb)
    np.testing.assert_array_equal(a.foreground, b.foreground)
    np.testing.assert_array_equal(a.instances.labels, b.instances.labels)


def test_tta_is_deterministic_and_a_predictor_keeps_its_network(random_model: Path):
    rgb = _image(2)
    p = Predictor(random_model, num_threads=1, tta="flips+rot180")
    first = p.predict(rgb)
    second = p.predict(rgb)
    np.testing.assert_array_equal(first.foreground, second.foreground)
    np.testing.assert_array_equal(first.suction, second.suction)
    np.testing.assert_array_equal(first.instances.labels, second.instances.labels)
    again = Predictor(random_model, num_threads=1, tta="flips+rot180").predict(rgb)
    np.testing.assert_array_equal(first.foreground, again.foreground)
    other = p.with_tta("flips")
    assert other.model is p.model
    assert (p.tta, other.tta) == ("flips+rot180", "flips")


def test_bad_tta_names_the_setting(random_model: Path, tmp_path: Path):
    for bad in ("flip", "", "FLIPS", None, 3):
        with pytest.raises(InvalidArgumentError, match=r"tta \(test-time augmentation\)"):
            Predictor(random_model, tta=bad)  # type: ignore[arg-type]
    p = Predictor(random_model, num_threads=1)
    with pytest.raises(InvalidArgumentError, match="dihedral"):
        p.with_tta("rot90")
    img = tmp_path / "a.png"
    Image.fromarray(_image()).save(img)
    with pytest.raises(InvalidArgumentError, match="tta"):
        predict_files(random_model, [img], tmp_path / "out", tta="mirror", progress=False)


def _coco(folder: Path) -> Path:
    folder.mkdir()
    Image.fromarray(_image(4)).save(folder / "a.png")
    doc = {
        "images": [{"id": 1, "file_name": "a.png", "width": W, "height": H}],
        "annotations": [
            {
                "id": 1,
                "image_id": 1,
                "category_id": 1,
                "segmentation": [[8, 5, 30, 5, 30, 20, 8, 20]],
            }
        ],
        "categories": [{"id": 1, "name": "object"}],
    }
    (folder / "instances.json").write_text(json.dumps(doc))
    return folder


def test_tta_commands_record_the_setting(
    random_model: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
):
    img = tmp_path / "a.png"
    Image.fromarray(_image()).save(img)
    for mode in ("none", "flips"):
        out = tmp_path / f"pred_{mode}"
        args = ["predict", str(random_model), str(img), "--out", str(out), "--quiet"]
        assert main([*args, "--num-threads", "1", "--tta", mode]) == 0
        doc = json.loads((out / "predictions.json").read_text())
        assert doc["tta"] == mode
        want = Predictor(random_model, num_threads=1, tta=mode).predict(_image())
        ids = np.asarray(Image.open(out / "a_instances.png"))
        np.testing.assert_array_equal(ids, want.instances.labels)
    photos = _coco(tmp_path / "photos")
    out = tmp_path / "eval"
    args = ["eval", "real", str(photos), "--model", str(random_model), "--out", str(out)]
    assert main([*args, "--quiet", "--num-threads", "1", "--tta", "dihedral"]) == 0
    assert "test-time augmentation dihedral" in capsys.readouterr().out
    doc = json.loads((out / "results.json").read_text())
    assert doc["tta"] == "dihedral"
    want = evaluate_real(
        Predictor(random_model, num_threads=1, tta="dihedral"), photos, progress=False
    )
    assert doc["summary"]["fg_IoU"] == want.foreground_iou
    with pytest.raises(SystemExit):
        main([*args, "--tta", "rot45"])
    assert "--tta: invalid choice: 'rot45'" in capsys.readouterr().err
