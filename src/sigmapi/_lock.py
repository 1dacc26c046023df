"""One command at a time per output: an exclusive, non-blocking lock beside what it writes.

``with output_lock(path, "--out folder"):`` holds an advisory lock (``flock``) on the lock
file :func:`lock_path` of ``path`` (a folder: ``DIR/.sigmapi.lock``; a file:
``.NAME.sigmapi.lock`` beside it) while the command writes. A second command on the same
output raises :class:`~sigmapi.errors.UsageError` at once, naming the holder's pid and the fix,
instead of both writing and one losing. The kernel drops the lock when its holder dies
(SIGKILL too), so a stale lock file never blocks; the file is removed on release. The lock
file is opened with ``O_NOFOLLOW`` and must be a regular file owned by this user: a link
planted there (to a file a command would otherwise truncate) or a FIFO is refused, naming
it. Within one process the lock is re-entrant (a sweep run from the command line takes it
twice). Where ``fcntl`` is missing (Windows), nothing is locked.
"""

from __future__ import annotations

import contextlib
import os
import stat
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


def _open(lock: Path, what: str) -> int:
    """Open (or make) the lock file: never through a link, only a regular file this user owns."""
    flags = os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
    try:
        fd = os.open(lock, flags, 0o644)
    except OSError as exc:
        hint = (
            "it is a symbolic link, which sigmapi never follows: remove it"
            if os.path.islink(lock)
            else "check the folder's permissions, or choose another output"
        )
        raise UsageError(
            f"cannot open the lock file {str(lock)!r} of {what}: {exc.strerror or exc}; {hint}"
        ) from None
    st = os.fstat(fd)
    problem = None
    if not stat.S_ISREG(st.st_mode):
        problem = "is not a regular file (a FIFO or device?)"
    elif hasattr(os, "getuid") and st.st_uid != os.getuid():
        problem = f"belongs to another user (uid {st.st_uid})"
    if problem is not None:
        os.close(fd)
        raise UsageError(
            f"the lock file {str(lock)!r} of {what} {problem}; remove it, or choose another output"
        )
    return fd


def _acquire(lock: Path, what: str) -> int:
    while True:
        fd = _open(lock, what)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            try:
                holder = os.read(fd, 32).decode("ascii", "replace").strip() or "?"
            except OSError:
                holder = "?"
            finally:
                os.close(fd)
            raise UsageError(
                f"{what} is in use by another sigmapi command (pid {holder}); wait for it to "
                f"finish, or choose another output"
            ) from None
        try:  # the holder may have removed the file between our open and our lock: retry
            same = os.stat(lock, follow_symlinks=False).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            try:
                os.ftruncate(fd, 0)
                os.write(fd, f"{os.getpid()}\n".encode("ascii"))
            except OSError as exc:  # a full disk: no lock left behind, no fd leaked
                with contextlib.suppress(OSError):
                    os.unlink(lock)
                os.close(fd)
                raise UsageError(
                    f"cannot write the lock file {str(lock)!r} of {what}: "
                    f"{exc.strerror or exc}; free space or choose another "
                    "output"
                ) from None
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
    key = str(lock.parent.resolve() / lock.name)
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
