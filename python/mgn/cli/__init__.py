"""The ``mgn`` command line: one module per command group, wired together in :mod:`mgn.cli.main`.

The top layer of the package (docs/architecture.md): it may import every other layer, nothing
imports it (``python -m mgn`` and the ``mgn`` script call :func:`main`).
"""

from mgn.cli.main import main

__all__ = ["main"]
