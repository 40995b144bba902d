"""Atomic writes: nothing is ever left half-written.

Files are written to a temporary name in the same directory and renamed into place; folders are
built under a temporary name and renamed when complete. Both get the usual permissions of a new
file or folder (0666 / 0777 less the umask), not the private ones of a temporary name. A full
disk is reported as such (:func:`disk_full_error`, :func:`disk_full_message`).
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from mgn.errors import IoError

#: How HDF5 (through h5py) words a full disk inside its error text.
_HDF5_ENOSPC = ("errno = 28,", "No space left on device")


def disk_full_error(e: BaseException) -> BaseException | None:
    """The error in the chain of ``e`` (``__cause__`` / ``__context__``) that says the disk is
    full, if any: an OSError with ``errno.ENOSPC``, a message starting with "disk full", or an
    HDF5 error whose text carries errno 28 (h5py raises some of those as RuntimeError)."""
    seen = set()
    cur: BaseException | None = e
    while cur is not None and id(cur) not in seen:
        seen.add(id(cur))
        text = str(cur)
        if (isinstance(cur, OSError) and cur.errno == errno.ENOSPC) or text.startswith("disk full"):
            return cur
        if isinstance(cur, (OSError, RuntimeError)) and any(t in text for t in _HDF5_ENOSPC):
            return cur
        cur = cur.__cause__ or cur.__context__
    return None


def disk_full_message(path: str | os.PathLike[str]) -> str:
    """The one wording of a full disk: "disk full while writing '<path>': free some space and
    retry"."""
    return f"disk full while writing '{os.fspath(path)}': free some space and retry"


def _io_error(path: str | os.PathLike[str], e: BaseException) -> IoError:
    if disk_full_error(e) is not None:
        return IoError(disk_full_message(path))
    detail = e.strerror if isinstance(e, OSError) and e.strerror else e
    return IoError(f"cannot write '{os.fspath(path)}': {detail}")


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def _atomic_stream(path: str | os.PathLike[str], mode: str) -> Iterator[IO[Any]]:
    """The one temp-file-and-rename mechanism: ``mode`` "wb" (bytes) or "w" (UTF-8 text)."""
    target = Path(path)
    tmp = None
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
        os.fchmod(fd, 0o666 & ~_umask())  # mkstemp makes 0600 files; use the usual permissions
        encoding = None if "b" in mode else "utf-8"
        with os.fdopen(fd, mode, encoding=encoding) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        Path(tmp).replace(target)
        tmp = None
    except OSError as e:
        raise _io_error(target, e) from e
    finally:
        if tmp is not None:
            with contextlib.suppress(OSError):
                Path(tmp).unlink()


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> None:
    """Write ``data`` to ``path`` via a temporary file in the same folder and a rename."""
    with _atomic_stream(path, "wb") as fh:
        fh.write(data)


def atomic_write_text(path: str | os.PathLike[str], text: str) -> None:
    """Write UTF-8 ``text`` to ``path`` atomically."""
    atomic_write_bytes(path, text.encode("utf-8"))


@contextlib.contextmanager
def atomic_open(path: str | os.PathLike[str]) -> Iterator[IO[str]]:
    """A UTF-8 text stream whose content replaces ``path`` when the block succeeds (written to
    a temporary file in the same folder, then renamed); if the block raises, ``path`` is
    untouched. For files too large to build in memory first."""
    with _atomic_stream(path, "w") as fh:
        yield fh


@contextlib.contextmanager
def atomic_dir(path: str | os.PathLike[str], *, overwrite: bool = False) -> Iterator[Path]:
    """Build a folder under a temporary name; rename it to ``path`` when the block succeeds.

    If the block raises, the temporary folder is removed and ``path`` is untouched. With
    ``overwrite`` an existing ``path`` is replaced (the old one is removed only after the new one
    is complete); without it an existing ``path`` is an error.
    """
    target = Path(path)
    if target.exists() and not overwrite:
        raise IoError(f"'{target}' already exists; pass overwrite=True to replace it")
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent))
        tmp.chmod(0o777 & ~_umask())  # mkdtemp makes 0700 folders; use the usual permissions
    except OSError as e:
        raise _io_error(target, e) from e
    try:
        yield tmp
        old = None
        if target.exists():
            old = target.with_name(f".{target.name}.old-{os.getpid()}")
            target.replace(old)
        tmp.replace(target)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except OSError as e:
        shutil.rmtree(tmp, ignore_errors=True)
        raise _io_error(target, e) from e
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
