"""``mgn eval ...``: score predictions against a dataset's labels.

Each evaluation module listed in ``_MODULES`` has a ``register(eval_sub)`` function that adds its
action (``detections``, ``grasps``, ``layout``, ...) to the ``eval`` subparsers.
"""

from __future__ import annotations

import argparse
import importlib

__all__ = ["register"]

# One _MODULES.append("mgn.eval.<module>") line per evaluation module (each defines
# register(eval_sub)), added after the next line.
_MODULES: list[str] = []
_MODULES.append("mgn.eval.detections")
_MODULES.append("mgn.eval.layout_metrics")
_MODULES.append("mgn.eval.grasps")


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``eval`` command group to the ``mgn`` subparsers."""
    p = sub.add_parser("eval", help="score predictions against a dataset's labels")
    eval_sub = p.add_subparsers(dest="eval_command", metavar="ACTION", required=True)
    for name in _MODULES:
        importlib.import_module(name).register(eval_sub)
