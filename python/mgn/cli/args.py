"""Argument types and option blocks shared by the command modules of :mod:`mgn.cli`.

- Types: :func:`split_list` (``a b c`` or ``a,b,c``), :func:`int_list`, :func:`grasp_kind_arg`.
- Blocks: :func:`add_engine_arguments` (``--engine``, ``--spp`` of a command that renders, applied
  by :func:`engine_settings`), :func:`add_device_arguments` (``--device``, ``--num-threads`` of a
  PyTorch command),
  :func:`add_quiet_argument`, :func:`add_instance_threshold_arguments` (``--threshold``,
  ``--core-threshold`` of a model's instance masks), with :func:`device_kwargs` and
  :func:`instance_threshold_kwargs` turning the parsed values into keyword arguments;
  :func:`add_tta_argument` (``--tta``, the test-time augmentation of a model's predictions).
"""

from __future__ import annotations

import argparse
from typing import TypedDict

from mgn.errors import InvalidArgumentError
from mgn.hardware import normalize_grasp_kind
from mgn.learn.predict import DEFAULT_TTA, TTA_MODES
from mgn.render.settings import ENGINES, RenderSettings, with_engine

__all__ = [
    "DeviceKwargs",
    "InstanceThresholdKwargs",
    "add_device_arguments",
    "add_engine_arguments",
    "add_instance_threshold_arguments",
    "add_quiet_argument",
    "add_tta_argument",
    "device_kwargs",
    "engine_settings",
    "grasp_kind_arg",
    "instance_threshold_kwargs",
    "int_list",
    "split_list",
]


def split_list(values: str | list[str] | None) -> list[str] | None:
    """Object names or ids given as ``a b c`` or ``a,b,c`` (both forms in every command)."""
    if values is None:
        return None
    items = [values] if isinstance(values, str) else values
    return [t.strip() for v in items for t in v.split(",") if t.strip()]


def int_list(values: list[str] | None) -> list[int] | None:
    """:func:`split_list` of whole numbers (``1 2 3`` or ``1,2,3``)."""
    items = split_list(values)
    return None if items is None else [int(v) for v in items]


def grasp_kind_arg(text: str) -> str:
    """argparse ``type=`` of a grasp kind: the normalised name, or a usage error listing them."""

    try:
        return normalize_grasp_kind(text)
    except InvalidArgumentError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


class DeviceKwargs(TypedDict):
    """``device``, ``num_threads`` and ``progress`` of a PyTorch command."""

    device: str
    num_threads: int
    progress: bool


class InstanceThresholdKwargs(TypedDict):
    """``threshold`` and ``core_threshold`` of a model's instance masks."""

    threshold: float
    core_threshold: float


def add_device_arguments(
    p: argparse.ArgumentParser,
    *,
    device_help: str = "auto, cpu or cuda[:N]",
    threads_help: str = "torch CPU threads (0 = default)",
) -> None:
    """``--device`` (default ``auto``) and ``--num-threads`` (default 0) of a PyTorch command."""
    p.add_argument("--device", default="auto", help=device_help)
    p.add_argument("--num-threads", type=int, default=0, help=threads_help)


def add_quiet_argument(p: argparse.ArgumentParser, help_text: str = "no progress bar") -> None:
    """``--quiet``: no progress output."""
    p.add_argument("--quiet", action="store_true", help=help_text)


def device_kwargs(args: argparse.Namespace) -> DeviceKwargs:
    """The parsed :func:`add_device_arguments` and :func:`add_quiet_argument` values."""
    return {"device": args.device, "num_threads": args.num_threads, "progress": not args.quiet}


def add_instance_threshold_arguments(p: argparse.ArgumentParser) -> None:
    """``--threshold`` (foreground probability, default 0.5) and ``--core-threshold`` (instance
    seeds, default 0.4)."""
    p.add_argument("--threshold", type=float, default=0.5, help="foreground probability threshold")
    p.add_argument(
        "--core-threshold",
        type=float,
        default=0.4,
        help="core threshold of the instance seeds (lower: fewer, larger instances)",
    )


def instance_threshold_kwargs(args: argparse.Namespace) -> InstanceThresholdKwargs:
    """The parsed :func:`add_instance_threshold_arguments` values."""
    return {"threshold": args.threshold, "core_threshold": args.core_threshold}


def add_tta_argument(p: argparse.ArgumentParser) -> None:
    """``--tta`` (test-time augmentation, :data:`mgn.learn.predict.TTA_MODES`, default
    :data:`mgn.learn.predict.DEFAULT_TTA`)."""
    p.add_argument(
        "--tta",
        choices=tuple(TTA_MODES),
        default=DEFAULT_TTA,
        help="test-time augmentation: average the maps of the image and its mirrored / turned "
        "copies; costs one forward pass per copy: none 1, flips 3 (left-right and upside-down "
        f"mirrors), flips+rot180 4, dihedral 8 (default {DEFAULT_TTA})",
    )


def add_engine_arguments(parser: argparse.ArgumentParser, what: str = "the RGB images") -> None:
    """Add ``--engine {raster,path}`` and ``--spp N`` to ``parser`` (both default to the
    configuration's ``render`` section; :func:`engine_settings` applies them)."""
    parser.add_argument(
        "--engine",
        choices=ENGINES,
        default=None,
        help=f"what makes {what}: raster (fast OpenGL preview) or path (path tracer); "
        "default: config render.engine",
    )
    parser.add_argument(
        "--spp",
        type=int,
        default=None,
        metavar="N",
        help="path tracer samples per pixel (default: config render.spp)",
    )


def engine_settings(settings: RenderSettings, args: argparse.Namespace) -> RenderSettings:
    """``settings`` with the parsed ``--engine`` / ``--spp`` applied
    (:func:`mgn.render.settings.with_engine`; InvalidArgumentError naming ``--spp``)."""
    return with_engine(settings, getattr(args, "engine", None), getattr(args, "spp", None))
