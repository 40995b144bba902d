"""PyTorch, the one optional dependency of :mod:`mgn.learn`: import, device and determinism.

``torch`` is imported inside functions only, so ``import mgn`` and every ``mgn`` command work
without it; :func:`require_torch` names the extra to install when it is missing.
"""

from __future__ import annotations

import os
from typing import Any

from mgn.errors import InvalidArgumentError, UnsupportedError

__all__ = ["INSTALL_HINT", "choose_device", "require_torch", "seed_everything"]

#: How to install the learning extra (a CPU build of PyTorch first keeps pip from pulling a
#: CUDA build of several GB).
INSTALL_HINT = "pip install torch==2.13.0 && pip install 'mgn[learn]'"


def require_torch() -> Any:
    """The ``torch`` module; :class:`~mgn.errors.UnsupportedError` naming ``mgn[learn]`` when
    PyTorch is not installed."""
    try:
        import torch
    except ImportError as e:
        raise UnsupportedError(
            f"mgn's learning commands need PyTorch, which is not installed ({e}); install the "
            f"extra mgn[learn]: {INSTALL_HINT}"
        ) from None
    return torch


def choose_device(device: str = "auto") -> Any:
    """A ``torch.device``: ``"auto"`` (default) is the first CUDA GPU when torch finds one, else
    the CPU; ``"cpu"``, ``"cuda"`` or ``"cuda:N"`` pick one explicitly."""
    torch = require_torch()
    if device == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if device == "cpu" or device.startswith("cuda"):
        if device.startswith("cuda") and not torch.cuda.is_available():
            raise InvalidArgumentError(f"device {device!r}: torch finds no CUDA GPU")
        return torch.device(device)
    raise InvalidArgumentError(f"device must be 'auto', 'cpu' or 'cuda[:N]', got {device!r}")


def seed_everything(seed: int, num_threads: int, device: Any) -> None:
    """Seed torch, use deterministic kernels and ``num_threads`` intra-op CPU threads (0 = torch's
    default). The same seed and thread count give the same weights on the CPU; on a GPU the
    deterministic cuBLAS workspace is requested too (``CUBLAS_WORKSPACE_CONFIG``)."""
    torch = require_torch()
    if num_threads < 0:
        raise InvalidArgumentError(f"num_threads must be >= 0, got {num_threads}")
    if num_threads:
        torch.set_num_threads(num_threads)
    if device.type == "cuda":
        os.environ.setdefault("CUBLAS_WORKSPACE_CONFIG", ":4096:8")
        torch.backends.cudnn.benchmark = False
    torch.use_deterministic_algorithms(True, warn_only=device.type == "cuda")
    torch.manual_seed(seed)
