"""The exceptions raised by mgn.

Every error derives from :class:`MgnError` and also from the builtin that fits, so callers can
catch either::

    MgnError
    ├── InvalidArgumentError  (also ValueError)   bad value, shape or range
    ├── InvalidTypeError      (also TypeError)    an argument of the wrong type
    ├── IoError               (also OSError)      a file cannot be read or written
    ├── UnsupportedError      (also ValueError)   a valid request this build does not support
    └── BackendError          (also RuntimeError) a third-party library failed

The classes are created by the compiled core so that C++ exceptions map onto them directly
(``InvalidTypeError`` has no C++ counterpart and is defined here). Code in mgn raises only these
classes, never a plain ``ValueError`` or ``TypeError`` (tests/python/test_architecture.py).
"""

from mgn._core.core import BackendError, InvalidArgumentError, IoError, MgnError, UnsupportedError

__all__ = [
    "BackendError",
    "InvalidArgumentError",
    "InvalidTypeError",
    "IoError",
    "MgnError",
    "UnsupportedError",
]


class InvalidTypeError(MgnError, TypeError):
    """An argument has the wrong type (also a TypeError)."""
