"""``mgn train``: train a baseline on the views of an mgn dataset.

One network (:mod:`mgn.learn.model`) learns, per pixel, the foreground, the normalised inner
distance of the objects ("core"), the suction quality and, for amodal models, the hidden parts
of objects (:mod:`mgn.learn.targets`). The loss is the sum of binary cross-entropies (soft
targets for core and suction): foreground (plus the soft Dice loss with
``foreground_loss="bce+dice"``, the default); core; suction weighted by the target's weight map
(known pixels only); hidden. Adam, with the learning rate cosine-decayed
from ``lr`` to 5 % of it over all steps. Each view of a batch is augmented
(:mod:`mgn.learn.augment`, ``TrainConfig.augment``).

Reproducibility: torch is seeded with ``TrainConfig.seed`` before the weights are made and uses
deterministic kernels (:func:`mgn.learn.backend.seed_everything`); the view order of epoch
``e`` comes from ``numpy.random.default_rng([seed, e])`` and the augmentation of view ``i`` in
it from ``numpy.random.default_rng([seed, e, i + 1])``. So the same seed and
thread count give the same weights on the CPU, and a run stopped after any epoch and continued
with ``resume=True`` ends with the weights of an uninterrupted run.

Files in ``out``: ``checkpoint.pt`` after every epoch, ``model.pt`` at the end
(:mod:`mgn.learn.checkpoint`) and ``train_log.json`` (configs, views, loss and seconds per
epoch).
"""

from __future__ import annotations

import json
import math
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from mgn._core import __version__
from mgn.base.atomic import atomic_write_text
from mgn.errors import InvalidArgumentError, IoError
from mgn.io.dataset import Dataset
from mgn.learn.augment import augment_view
from mgn.learn.backend import choose_device, require_torch, seed_everything
from mgn.learn.checkpoint import CHECKPOINT_FORMAT, MODEL_FORMAT, read_torch_file, write_torch_file
from mgn.learn.config import ModelConfig, TrainConfig, auto_epochs
from mgn.learn.data import TrainingArrays, load_views, training_views
from mgn.learn.model import (
    build_model,
    count_parameters,
    default_backbone_weights,
    load_backbone_weights,
)
from mgn.learn.targets import model_input

__all__ = ["TrainResult", "augmented_batch", "compute_losses", "dice_loss", "train"]


@dataclass
class TrainResult:
    """What :func:`train` did.

    Attributes:
        out_dir: the output folder; model_path: its ``model.pt``.
        num_views: training views; parameters: trainable parameters.
        history: per epoch {"epoch", "loss", "foreground", "core", "suction"[, "hidden"],
            "seconds"}.
        seconds: wall time of this call, s.
        device: the torch device used.
    """

    out_dir: Path
    model_path: Path
    num_views: int
    parameters: int
    history: list[dict[str, float]] = field(default_factory=list)
    seconds: float = 0.0
    device: str = "cpu"


def dice_loss(logits: Any, targets: Any) -> Any:
    """Soft Dice loss ``1 - 2 sum(p t) / (sum(p) + sum(t))`` over all pixels of a batch, ``p``
    the sigmoid of ``logits`` (0 when both are empty)."""
    p = require_torch().sigmoid(logits)
    inter = (p * targets).sum()
    total = p.sum() + targets.sum()
    return 1.0 - (2.0 * inter + 1.0) / (total + 1.0)


def compute_losses(
    logits: Any,
    targets: Any,
    weights: Any,
    config: ModelConfig,
    foreground_loss: str = "bce",
) -> dict[str, Any]:
    """The loss terms (scalar tensors) of a batch: logits and targets (B, T, H, W), suction
    weights (B, H, W); the foreground term is ``foreground_loss``
    (:data:`mgn.learn.config.FOREGROUND_LOSSES`); ``"loss"`` is their sum."""
    bce = require_torch().nn.functional.binary_cross_entropy_with_logits
    fg = bce(logits[:, 0], targets[:, 0])
    if foreground_loss == "bce+dice":
        fg = fg + dice_loss(logits[:, 0], targets[:, 0])
    out = {
        "foreground": fg,
        "core": bce(logits[:, 1], targets[:, 1]),
        "suction": (bce(logits[:, 2], targets[:, 2], reduction="none") * weights).sum()
        / weights.sum().clamp(min=1.0),
    }
    if config.amodal:
        out["hidden"] = bce(logits[:, 3], targets[:, 3])
    out["loss"] = sum(out.values())
    return out


def _param_groups(model: Any, tc: TrainConfig) -> list[dict[str, Any]]:
    """The encoder's parameters at ``encoder_lr_scale`` x the learning rate, the rest at 1 x."""
    encoder = getattr(model, "encoder", None)
    enc = list(encoder.parameters()) if encoder is not None else []
    ids = {id(p) for p in enc}
    rest = [p for p in model.parameters() if id(p) not in ids]
    groups = [{"params": rest, "lr_scale": 1.0}]
    if enc:
        groups.append({"params": enc, "lr_scale": float(tc.encoder_lr_scale)})
    return groups


def _lr(tc: TrainConfig, step: int, total: int) -> float:
    return tc.lr * (0.05 + 0.95 * 0.5 * (1.0 + math.cos(math.pi * step / max(total, 1))))


def _batches(n: int, tc: TrainConfig, epoch: int) -> list[np.ndarray]:
    """The view indices of each batch of an epoch."""
    order = np.random.default_rng([tc.seed, epoch]).permutation(n)
    return [order[i : i + tc.batch_size] for i in range(0, n, tc.batch_size)]


def augmented_batch(
    arrays: TrainingArrays,
    idx: np.ndarray,
    tc: TrainConfig,
    modality: str,
    epoch: int,
    rgb_norm: str = "none",
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Inputs, targets and weights of the views ``idx`` (positions in ``arrays``) as trained in
    ``epoch``: each view augmented with ``default_rng([seed, epoch, view + 1])``, then its RGB
    channels normalised by ``rgb_norm`` (:func:`mgn.learn.targets.model_input`)."""
    xs, ts, ws = [], [], []
    for i in idx:
        rng = np.random.default_rng([tc.seed, epoch, int(i) + 1])
        x, t, w = augment_view(
            arrays.inputs[i], arrays.targets[i], arrays.weights[i], tc.augment, modality, rng
        )
        xs.append(model_input(x, modality, rgb_norm))
        ts.append(t)
        ws.append(w)
    return np.stack(xs), np.stack(ts), np.stack(ws)


def _batch_tensors(
    arrays: TrainingArrays,
    idx: np.ndarray,
    tc: TrainConfig,
    mc: ModelConfig,
    epoch: int,
    device: Any,
) -> tuple[Any, ...]:
    torch = require_torch()
    return tuple(
        torch.from_numpy(a).to(device)
        for a in augmented_batch(arrays, idx, tc, mc.modality, epoch, mc.rgb_norm)
    )


def _start(
    out: Path, resume: bool, mc: ModelConfig, tc: TrainConfig, names: list[str]
) -> dict[str, Any] | None:
    """The checkpoint to continue from (None for a fresh run); errors when ``out`` holds
    another run."""
    ckpt_path = out / "checkpoint.pt"
    if not ckpt_path.exists():
        return None
    if not resume:
        raise IoError(
            f"'{out}' already holds a training run (checkpoint.pt): continue it with "
            "--resume, or train into another folder"
        )
    ckpt = read_torch_file(ckpt_path, CHECKPOINT_FORMAT)
    before = ModelConfig.from_saved(ckpt["model_config"]).to_dict() | ckpt["train_config"]
    now = mc.to_dict() | tc.to_dict()
    changed = [f"{k} {before.get(k)!r} -> {now.get(k)!r}" for k in now if before.get(k) != now[k]]
    if changed:
        raise InvalidArgumentError(
            f"--resume: '{ckpt_path}' was made with other settings ({'; '.join(changed)}); "
            "resume with the same settings, or train into another folder"
        )
    if ckpt["views"] != names:
        raise InvalidArgumentError(
            f"--resume: '{ckpt_path}' was trained on other views "
            f"({len(ckpt['views'])} views, now {len(names)})"
        )
    return ckpt


def _model_file(model: Any, mc: ModelConfig, meta: dict[str, Any]) -> dict[str, Any]:
    return {
        "format": MODEL_FORMAT,
        "model_config": mc.to_dict(),
        "training": meta,
        "state_dict": {k: v.detach().cpu() for k, v in model.state_dict().items()},
    }


def _init_model(
    model: Any,
    mc: ModelConfig,
    init: str | os.PathLike[str] | None,
    backbone_weights: str | os.PathLike[str] | None,
) -> None:
    if backbone_weights is None and init is None:
        backbone_weights = default_backbone_weights(mc.backbone)
    if backbone_weights is not None:
        load_backbone_weights(model, backbone_weights)
    if init is not None:
        src = read_torch_file(init, MODEL_FORMAT)
        other = ModelConfig.from_saved(src["model_config"])
        if (other.backbone, other.width, other.modality, other.amodal) != (
            mc.backbone,
            mc.width,
            mc.modality,
            mc.amodal,
        ):
            raise InvalidArgumentError(
                f"--init '{init}': its model ({other.backbone}, width {other.width}, "
                f"{other.modality}, amodal {other.amodal}) differs from the one trained "
                f"({mc.backbone}, width {mc.width}, {mc.modality}, amodal {mc.amodal})"
            )
        model.load_state_dict(src["state_dict"])


def train(
    dataset: Dataset | str | os.PathLike[str],
    out: str | os.PathLike[str],
    *,
    model_config: ModelConfig | None = None,
    train_config: TrainConfig | None = None,
    scenes: Sequence[int] | None = None,
    views: Sequence[int] | None = None,
    resume: bool = False,
    device: str = "auto",
    num_threads: int = 0,
    init: str | os.PathLike[str] | None = None,
    backbone_weights: str | os.PathLike[str] | None = None,
    progress: bool = True,
) -> TrainResult:
    """Train a baseline on ``dataset`` into the folder ``out`` (module docstring).

    Args:
        dataset: an mgn dataset folder (or :class:`mgn.Dataset`).
        out: output folder (created).
        model_config, train_config: defaults when None.
        scenes, views: only these scene ids / view indices (default: all, or the dataset's
            selection).
        resume: continue the run in ``out`` from its ``checkpoint.pt``.
        device: ``auto`` (a CUDA GPU when torch finds one), ``cpu`` or ``cuda[:N]``.
        num_threads: torch CPU threads (0 = torch's default).
        init: an mgn ``model.pt`` to start from (same backbone, width, input and outputs).
        backbone_weights: a local ImageNet state-dict file for the ``resnet18`` or
            ``efficientnet_lite0`` encoder (default: none for ``resnet18``, the installed
            package's file for ``efficientnet_lite0``, :func:`default_backbone_weights`).
        progress: show a progress bar with the running loss.
    """
    t0 = time.perf_counter()
    torch = require_torch()
    mc = model_config or ModelConfig()
    tc = train_config or TrainConfig()
    out_dir = Path(out)
    selected = training_views(dataset, scenes=scenes, views=views)
    names = [f"{v.folder.name}/{v.index}" for v in selected]
    epochs = auto_epochs(len(names)) if tc.epochs is None else int(tc.epochs)
    tc = replace(tc, epochs=epochs)  # the files record the epochs run
    ckpt = _start(out_dir, resume, mc, tc, names)
    dev = choose_device(device)
    seed_everything(tc.seed, num_threads, dev)
    arrays = load_views(selected, mc)
    model = build_model(mc)
    if ckpt is None:
        _init_model(model, mc, init, backbone_weights)
    model.to(dev)
    optimizer = torch.optim.Adam(_param_groups(model, tc), lr=tc.lr)
    history: list[dict[str, float]] = []
    first_epoch = 0
    if ckpt is not None:
        model.load_state_dict(ckpt["state_dict"])
        optimizer.load_state_dict(ckpt["optimizer"])
        history = list(ckpt["history"])
        first_epoch = int(ckpt["epoch"])
    out_dir.mkdir(parents=True, exist_ok=True)
    steps_per_epoch = math.ceil(len(arrays) / tc.batch_size)
    total = epochs * steps_per_epoch
    meta: dict[str, Any] = {
        "dataset": os.fspath(Path(dataset.root if isinstance(dataset, Dataset) else dataset)),
        "views": names,
        "train_config": tc.to_dict(),
        "mgn_version": __version__,
        "torch_version": str(torch.__version__),
        "device": str(dev),
    }
    bar = tqdm(
        total=total,
        initial=first_epoch * steps_per_epoch,
        desc="train",
        unit="step",
        disable=not progress,
        dynamic_ncols=True,
    )
    model.train()
    for epoch in range(first_epoch, epochs):
        te = time.perf_counter()
        sums: dict[str, float] = {}
        for k, idx in enumerate(_batches(len(arrays), tc, epoch)):
            step = epoch * steps_per_epoch + k
            for group in optimizer.param_groups:
                group["lr"] = _lr(tc, step, total) * group["lr_scale"]
            x, t, w = _batch_tensors(arrays, idx, tc, mc, epoch, dev)
            losses = compute_losses(model(x), t, w, mc, tc.foreground_loss)
            optimizer.zero_grad(set_to_none=True)
            losses["loss"].backward()
            optimizer.step()
            for name, value in losses.items():
                sums[name] = sums.get(name, 0.0) + float(value.detach()) * len(idx)
            bar.update(1)
            bar.set_postfix(epoch=epoch + 1, loss=f"{sums['loss'] / ((k + 1) * tc.batch_size):.4f}")
        row = {"epoch": epoch + 1, **{n: s / len(arrays) for n, s in sums.items()}}
        row["seconds"] = time.perf_counter() - te
        history.append(row)
        write_torch_file(
            out_dir / "checkpoint.pt",
            {
                "format": CHECKPOINT_FORMAT,
                "model_config": mc.to_dict(),
                "train_config": tc.to_dict(),
                "views": names,
                "epoch": epoch + 1,
                "state_dict": {k: v.detach().cpu() for k, v in model.state_dict().items()},
                "optimizer": optimizer.state_dict(),
                "history": history,
            },
        )
    bar.close()
    meta["history"] = history
    write_torch_file(out_dir / "model.pt", _model_file(model, mc, meta))
    log = {"model_config": mc.to_dict(), **meta, "parameters": count_parameters(model)}
    atomic_write_text(out_dir / "train_log.json", json.dumps(log, indent=1) + "\n")
    return TrainResult(
        out_dir,
        out_dir / "model.pt",
        len(arrays),
        count_parameters(model),
        history,
        time.perf_counter() - t0,
        str(dev),
    )
