"""The exceptions raised by mgn.

Every error derives from :class:`MgnError` and also from the builtin that fits, so callers can
catch either::

    MgnError
    ├── InvalidArgumentError  (also ValueError)   bad value, shape or range
    ├── IoError               (also OSError)      a file cannot be read or written
    ├── UnsupportedError      (also ValueError)   a valid request this build does not support
    └── BackendError          (also RuntimeError) a third-party library failed

The classes are created by the compiled core so that C++ exceptions map onto them directly.
"""

from mgn._core import BackendError, InvalidArgumentError, IoError, MgnError, UnsupportedError

__all__ = ["MgnError", "InvalidArgumentError", "IoError", "UnsupportedError", "BackendError"]
