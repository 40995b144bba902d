"""
mgn/core: errors, build information, threads.
"""

from __future__ import annotations

import typing

__all__: list[str] = [
    "BackendError",
    "InvalidArgumentError",
    "IoError",
    "MgnError",
    "UnsupportedError",
    "build_info",
    "resolve_num_threads",
]

class MgnError(Exception):
    """
    Base class of every error raised by mgn.
    """

class InvalidArgumentError(MgnError, ValueError):
    """
    An argument has a wrong value, shape or range (also a ValueError).
    """

class IoError(MgnError, OSError):
    """
    A file could not be read or written (also an OSError).
    """

class UnsupportedError(MgnError, ValueError):
    """
    A valid request that this build or format does not support (also a ValueError).
    """

class BackendError(MgnError, RuntimeError):
    """
    A third-party backend reported a failure (also a RuntimeError).
    """

def build_info() -> list[tuple[str, str]]:
    """
    (library, version) pairs for mgn and every library the core was built against.
    """

def resolve_num_threads(requested: typing.SupportsInt | typing.SupportsIndex) -> int:
    """
    Thread count used for `requested` (0 = all hardware threads).
    """
