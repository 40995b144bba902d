"""``mgn train``, ``mgn predict`` and ``mgn transfer``: the learning baselines (:mod:`mgn.learn`).

This module only parses the arguments; PyTorch is needed when a command runs, not to build the
parser (``mgn --help`` works without it).
"""

from __future__ import annotations

import argparse

from mgn.cli.args import (
    add_device_arguments,
    add_instance_threshold_arguments,
    add_quiet_argument,
    add_tta_argument,
    device_kwargs,
    instance_threshold_kwargs,
    int_list,
)
from mgn.learn.augment import AUGMENTS
from mgn.learn.config import (
    BACKBONES,
    FOREGROUND_LOSSES,
    SUCTION_SCORES,
    TRAINING_FLOORS,
    ModelConfig,
    TrainConfig,
)
from mgn.learn.predict import predict_files
from mgn.learn.targets import MODALITIES, RGB_NORMS
from mgn.learn.training import train
from mgn.learn.transfer import run_transfer

__all__ = ["add_model_arguments", "add_train_arguments", "configs_from_args", "register"]


def add_model_arguments(p: argparse.ArgumentParser) -> None:
    """The :class:`ModelConfig` options."""
    d = ModelConfig()
    p.add_argument(
        "--modality",
        choices=MODALITIES,
        default=d.modality,
        help="network input: rgb, depth (the sensor model's depth), rgbd, height (height above "
        "the depth's fitted floor plane) or rgb-height",
    )
    p.add_argument(
        "--image-size",
        type=int,
        default=d.image_size,
        metavar="PX",
        help="longer image side the network sees, px",
    )
    p.add_argument("--amodal", action="store_true", help="also predict amodal masks")
    p.add_argument(
        "--backbone",
        choices=BACKBONES,
        default=d.backbone,
        help="small U-Net (trained from scratch), ResNet-18 or EfficientNet-Lite0 encoder "
        "(ImageNet weights: see --backbone-weights)",
    )
    p.add_argument("--width", type=int, default=d.width, help="channels of the small U-Net")
    p.add_argument(
        "--suction-radius",
        type=float,
        default=d.suction_radius_m,
        metavar="M",
        help="radius of the disc each suction label marks, m",
    )
    p.add_argument(
        "--suction-score",
        choices=SUCTION_SCORES,
        default=d.suction_score,
        help="the suction label score learned",
    )
    p.add_argument(
        "--rgb-norm",
        choices=RGB_NORMS,
        default=d.rgb_norm,
        help="per-image normalisation of the RGB input: image (the default: each channel "
        "standardised over its image; exposure and white balance do not matter) or none (RGB "
        "as read)",
    )
    p.add_argument(
        "--floor-footprint",
        action="store_true",
        default=d.floor_footprint,
        help="height and rgb-height: the height is 0 outside the floor's footprint (the convex "
        "hull of the floor's pixels: a bin's walls and rim read as floor)",
    )
    p.add_argument(
        "--training-floor",
        choices=TRAINING_FLOORS,
        default=d.training_floor,
        help="height and rgb-height: the training views' floor from the scene's own geometry "
        "(the bin's inner floor) with the footprint of its visible pixels (scene, the default) "
        "or the inside of the bin's walls (interior), or fitted to their depth as for a "
        "photograph (fit)",
    )


def add_train_arguments(p: argparse.ArgumentParser) -> None:
    """The :class:`TrainConfig` options and the device."""
    d = TrainConfig()
    p.add_argument(
        "--epochs",
        type=int,
        default=d.epochs,
        help="passes over the training views (default: 40, more for datasets under 120 views "
        "so that a run makes 4,800 view passes, at most 80)",
    )
    p.add_argument("--batch-size", type=int, default=d.batch_size, help="views per step")
    p.add_argument("--lr", type=float, default=d.lr, help="Adam learning rate (cosine decay)")
    p.add_argument("--seed", type=int, default=d.seed, help="weights, view order and augmentation")
    p.add_argument(
        "--augment",
        choices=AUGMENTS,
        default=d.augment,
        help="full: random zoom, 90-degree turns, flips, colour/blur/noise/JPEG; flips; none",
    )
    p.add_argument("--no-augment", action="store_true", help="the same as --augment none")
    p.add_argument(
        "--foreground-loss",
        choices=FOREGROUND_LOSSES,
        default=d.foreground_loss,
        help="loss of the foreground channel",
    )
    p.add_argument(
        "--encoder-lr-scale",
        type=float,
        default=d.encoder_lr_scale,
        metavar="F",
        help="the encoder's learning rate as a fraction of --lr, in (0, 1]",
    )
    add_device_arguments(
        p,
        device_help="auto (a CUDA GPU if torch finds one), cpu or cuda[:N]",
        threads_help="torch CPU threads (0 = torch's default; fix it for reproducible weights)",
    )


def configs_from_args(args: argparse.Namespace) -> tuple[ModelConfig, TrainConfig]:
    """The configs of parsed :func:`add_model_arguments` / :func:`add_train_arguments`."""
    mc = ModelConfig(
        modality=args.modality,
        image_size=args.image_size,
        amodal=args.amodal,
        backbone=args.backbone,
        width=args.width,
        suction_radius_m=args.suction_radius,
        suction_score=args.suction_score,
        rgb_norm=args.rgb_norm,
        floor_footprint=args.floor_footprint,
        training_floor=args.training_floor,
    )
    tc = TrainConfig(
        epochs=args.epochs,
        batch_size=args.batch_size,
        lr=args.lr,
        seed=args.seed,
        augment="none" if args.no_augment else args.augment,
        foreground_loss=args.foreground_loss,
        encoder_lr_scale=args.encoder_lr_scale,
    )
    return mc, tc


def _cmd_train(args: argparse.Namespace) -> int:
    mc, tc = configs_from_args(args)
    res = train(
        args.dataset,
        args.out,
        model_config=mc,
        train_config=tc,
        scenes=int_list(args.scenes),
        views=int_list(args.views),
        resume=args.resume,
        init=args.init,
        backbone_weights=args.backbone_weights,
        **device_kwargs(args),
    )
    last = res.history[-1] if res.history else {}
    print(
        f"trained on {res.num_views} views ({res.parameters:,} parameters, {res.device}) in "
        f"{res.seconds:.1f} s; final loss {last.get('loss', float('nan')):.4f}"
    )
    print(f"model: {res.model_path}")
    return 0


def _cmd_predict(args: argparse.Namespace) -> int:
    path = predict_files(
        args.model,
        args.images,
        args.out,
        depths=args.depth,
        num_suction_points=args.suction_points,
        tta=args.tta,
        **instance_threshold_kwargs(args),
        **device_kwargs(args),
    )
    print(
        f"predictions of {len(args.images)} image(s): {path} (+ *_instances.png, "
        "*_suction.png, *_overlay.png)"
    )
    return 0


def _cmd_transfer(args: argparse.Namespace) -> int:
    res = run_transfer(
        args.spec,
        args.out,
        real=args.real,
        seeds=int_list(args.seeds),
        **device_kwargs(args),
    )
    print(res.markdown(), end="")
    print(f"wrote {args.out}/transfer.md, transfer.json, transfer.png")
    return 0


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``train``, ``predict`` and ``transfer`` to the ``mgn`` subparsers."""
    p = sub.add_parser(
        "train", help="train the segmentation + suction baseline on a dataset (needs mgn[learn])"
    )
    p.add_argument("dataset", help="mgn dataset folder")
    p.add_argument("--out", required=True, help="output folder (model.pt, checkpoint.pt, log)")
    p.add_argument("--scenes", nargs="+", metavar="N", help="only these scene ids")
    p.add_argument("--views", nargs="+", metavar="V", help="only these view indices")
    p.add_argument("--resume", action="store_true", help="continue the run in --out")
    p.add_argument("--init", metavar="MODEL", help="start from this model.pt (fine-tuning)")
    p.add_argument(
        "--backbone-weights",
        metavar="FILE",
        help="local ImageNet state dict of the encoder (ResNet-18 for --backbone resnet18, "
        "EfficientNet-Lite0 for efficientnet_lite0)",
    )
    add_quiet_argument(p)
    add_model_arguments(p)
    add_train_arguments(p)
    p.set_defaults(func=_cmd_train)

    p = sub.add_parser(
        "predict", help="instance masks and suction maps of images (needs mgn[learn])"
    )
    p.add_argument("model", help="model.pt of mgn train")
    p.add_argument("images", nargs="+", help="PNG or JPEG images")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument(
        "--depth",
        nargs="+",
        metavar="FILE",
        help="one depth file per image: .npy (m), .npz 'depth' (cm), 16-bit .png (mm)",
    )
    add_instance_threshold_arguments(p)
    p.add_argument("--suction-points", type=int, default=10, help="suction points per image")
    add_tta_argument(p)
    add_device_arguments(p)
    add_quiet_argument(p)
    p.set_defaults(func=_cmd_predict)

    p = sub.add_parser(
        "transfer",
        help="ablation: dataset variants x replicates (training and dataset seeds), scored on "
        "one real set and on every variant's held-out synthetic views (needs mgn[learn])",
    )
    p.add_argument("spec", help="transfer spec YAML (variants, seeds, real set; docs/learning.md)")
    p.add_argument(
        "--out", required=True, help="output folder (datasets, held-out sets, models, table, plot)"
    )
    p.add_argument("--real", help="labelled real set (overrides the spec's 'real')")
    p.add_argument("--seeds", nargs="+", metavar="S", help="training seeds (overrides the spec)")
    add_device_arguments(p)
    add_quiet_argument(p, "no progress bars")
    p.set_defaults(func=_cmd_transfer)
