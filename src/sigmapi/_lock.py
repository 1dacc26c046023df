"""One command at a time per output: an exclusive, non-blocking lock beside what it writes.

``with output_lock(path, "--out folder"):`` holds an advisory lock (``flock``) on the lock
file :func:`lock_path` of ``path`` (a folder: ``DIR/.sigmapi.lock``; a file:
``.NAME.sigmapi.lock`` beside it) while the command writes. A second command on the same
output raises :class:`~sigmapi.errors.UsageError` at once, naming the holder's pid and the fix,
instead of both writing and one losing. The kernel drops the lock when its holder dies
(SIGKILL too), so a stale lock file never blocks; the file is removed on release. Within one
process the lock is re-entrant (a sweep run from the command line takes it twice). Where
``fcntl`` is missing (Windows), nothing is locked.
"""

from __future__ import annotations

import contextlib
import os
import threading
from collections.abc import Iterator
from pathlib import Path

from sigmapi.errors import UsageError

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX
    fcntl = None  # type: ignore[assignment]

__all__ = ["LOCK_NAME", "lock_path", "output_lock"]

LOCK_NAME = ".sigmapi.lock"
"""The lock file in a locked folder (commands that check a folder is empty skip it)."""

_held: dict[str, int] = {}
_guard = threading.Lock()


def lock_path(path: str | Path) -> Path:
    """The lock file of ``path``: inside it if it is a folder, else beside it."""
    p = Path(path)
    if p.is_dir():
        return p / LOCK_NAME
    return p.parent / f".{p.name}{LOCK_NAME}"


def _acquire(lock: Path, what: str) -> int:
    while True:
        fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            try:
                holder = os.read(fd, 32).decode("ascii", "replace").strip() or "?"
            finally:
                os.close(fd)
            raise UsageError(
                f"{what} is in use by another sigmapi command (pid {holder}); wait for it to "
                f"finish, or choose another output"
            ) from None
        try:  # the holder may have removed the file between our open and our lock: retry
            same = os.stat(lock).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            os.ftruncate(fd, 0)
            os.write(fd, f"{os.getpid()}\n".encode("ascii"))
            return fd
        os.close(fd)


@contextlib.contextmanager
def output_lock(path: str | Path, what: str) -> Iterator[None]:
    """Hold the lock of ``path`` (a folder or a file; its folder must exist) for the block;
    ``what`` names the output in the error (e.g. ``"--out folder 'runs'"``)."""
    if fcntl is None:  # pragma: no cover - not POSIX
        yield
        return
    lock = lock_path(path)
    key = str(lock.resolve())
    with _guard:
        if key in _held:
            _held[key] += 1
            fd = None
        else:
            fd = _acquire(lock, what)
            _held[key] = 1
    try:
        yield
    finally:
        with _guard:
            _held[key] -= 1
            if _held[key] == 0:
                del _held[key]
                if fd is not None:
                    with contextlib.suppress(OSError):
                        os.unlink(lock)
                    os.close(fd)
