"""The one writer of the files a command writes, and the folder an experiment owns.

:func:`check_file` runs before the work: the path is no folder, device or link, an existing
file is only replaced with ``force``, the folder exists and takes files. :func:`write_file`
then writes it atomically (:func:`sigmapi.io.atomic_write`: a temporary file in the same
folder, fsync'ed, renamed over the target; a full disk leaves the old file, never a cut one)
and never through a symbolic link: a link is refused, or with ``force`` replaced by the file
(its target is left as it is).

An experiment's output folder holds one experiment: :func:`claim_folder` finds the marker file
:data:`MARKER` (``{"experiment": NAME}``) there, or writes it into a folder that is empty but
for the lock. A folder marked for another experiment is refused, ``--force`` or not; an
unmarked folder that holds anything is refused without ``force`` (a user's own
``result.json``, ``sweep.png`` or any other file is never replaced unasked).

No command writes over its own input (:func:`refuse_input_as_output`, which ``sigmapi``'s
entry point runs before every command): an output that is, by inode, one of the command's
input files (the same file, a hard link to it, or a symbolic link to it), or an output folder
that holds one, is refused before any work, ``--force`` or not (``cp`` refuses this case too).
A command declares its paths with :data:`INPUT` and :data:`OUTPUT` (field metadata of a
config, or by hand on its parser).
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import re
import stat
from collections.abc import Callable, Collection, Sequence
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from sigmapi._lock import LOCK_NAME
from sigmapi.errors import UsageError
from sigmapi.io import atomic_write, temp_name, temp_pattern

if TYPE_CHECKING:
    import numpy as np
    from matplotlib.figure import Figure
    from numpy.typing import NDArray

__all__ = [
    "INPUT",
    "MARKER",
    "OUTPUT",
    "check_file",
    "check_folder",
    "claim_folder",
    "marked_as",
    "refuse_input_as_output",
    "save_captioned",
    "save_figure",
    "save_gif",
    "write_file",
]

MARKER = ".sigmapi-experiment"
"""The file that marks a folder as one experiment's output (JSON: ``{"experiment": NAME}``)."""

_MAX_MARKER = 4096

INPUT: dict[str, str] = {"path": "input"}
"""Field metadata: the field names a file the command reads (:func:`refuse_input_as_output`)."""
OUTPUT: dict[str, str] = {"path": "output"}
"""Field metadata: the field names a file the command writes (:func:`refuse_input_as_output`)."""


def _identity(path: str | Path) -> tuple[int, int] | None:
    """``(st_dev, st_ino)`` of ``path``, through links (None: nothing is there)."""
    try:
        st = os.stat(path)
    except (OSError, ValueError):  # missing, unreadable, a NUL in the name: nothing to compare
        return None
    return st.st_dev, st.st_ino


def _within(path: str | Path) -> list[tuple[int, int]]:
    """The identities of ``path`` and of every folder above it, as written and as resolved."""
    p = Path(path).absolute()
    try:
        real = Path(os.path.realpath(p))
    except (OSError, ValueError):
        real = p
    ids = (_identity(q) for q in (p, *p.parents, real, *real.parents))
    return [i for i in ids if i is not None]


def refuse_input_as_output(
    outputs: Sequence[tuple[str, str | Path, bool]], inputs: Sequence[tuple[str, str | Path]]
) -> None:
    """Before the work: no output is one of the inputs, compared by inode (``st_dev`` and
    ``st_ino``, through symbolic and hard links); an output folder (the third item ``True``)
    holds none of them. ``outputs`` are ``(flag, path, is_folder)``, ``inputs`` ``(flag,
    path)``; raises :class:`~sigmapi.errors.UsageError`, ``--force`` or not."""
    for oflag, opath, folder in outputs:
        oid = _identity(opath)
        if oid is None:  # a file or folder still to be made holds nothing yet
            continue
        for iflag, ipath in inputs:
            if folder and oid in _within(ipath):
                raise UsageError(
                    f"{oflag} folder {str(opath)!r} holds the input {iflag} {str(ipath)!r}; "
                    f"sigmapi never writes where it may replace its input, --force or not: "
                    f"give another {oflag} (or move the input out of it)"
                )
            if not folder and oid == _identity(ipath):
                raise UsageError(
                    f"{oflag} {str(opath)!r} is the input {iflag} {str(ipath)!r} (the same "
                    f"file, by inode); sigmapi never writes over its input, --force or not: "
                    f"give another {oflag}"
                )


def _lstat(p: Path) -> os.stat_result | None:
    try:
        return p.lstat()
    except FileNotFoundError:
        return None
    except OSError as exc:
        raise UsageError(
            f"cannot access {str(p)!r}: {exc.strerror or exc}; choose another path"
        ) from None


def check_file(path: str | Path, *, force: bool, what: str = "output file") -> Path:
    """Before the work: ``path`` may be written by :func:`write_file` (see the module's
    docstring); raises :class:`~sigmapi.errors.UsageError` naming ``what`` and the fix."""
    p = Path(path)
    name = f"{what} {str(p)!r}"
    if str(path).endswith(os.sep) or p.name in ("", ".", ".."):
        raise UsageError(f"{name} names a folder; give a file name")
    st = _lstat(p)
    if st is not None:
        if stat.S_ISLNK(st.st_mode) and not force:
            raise UsageError(
                f"{name} is a symbolic link; sigmapi never writes through one: "
                "remove it, or pass --force to replace the link itself"
            )
        if stat.S_ISDIR(st.st_mode):
            raise UsageError(f"{name} is a folder; give a file name")
        if not (stat.S_ISREG(st.st_mode) or stat.S_ISLNK(st.st_mode)):
            raise UsageError(f"{name} is not a regular file (a device or FIFO?); give a file name")
        if not force:
            raise UsageError(f"{name} exists; pass --force to overwrite it")
    check_folder(p, name)
    return p


def check_folder(path: Path, name: str) -> None:
    """Before the work: the folder of ``path`` exists and takes files (a file made there and
    removed: found out now, not after a long run); ``name`` names the file in the one-line
    :class:`~sigmapi.errors.UsageError`."""
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise UsageError(f"folder {str(parent)!r} of {name} does not exist; create it first")
    name_first = temp_name(parent, path.name)  # named first: a signal cannot orphan it
    probe: Path | None = name_first
    try:
        os.close(os.open(name_first, os.O_RDWR | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600))
    except FileExistsError:
        probe = None  # another file by that name, not ours: left alone
    except OSError as exc:
        probe = None
        raise UsageError(
            f"cannot write {name}: cannot access its folder {str(parent)!r}: "
            f"{exc.strerror or exc}; choose another folder"
        ) from None
    finally:  # also when SIGTERM (SystemExit under the CLI) arrives right after the open
        if probe is not None:
            with contextlib.suppress(OSError):
                os.unlink(probe)


def write_file(
    path: str | Path,
    data: bytes | Callable[[IO[bytes]], None],
    *,
    force: bool = True,
    what: str = "output file",
) -> Path:
    """Write ``data`` (bytes, or a function writing to a binary file) to ``path`` atomically,
    never through a link; an existing file is replaced only with ``force`` (the default: a
    command checks its targets with :func:`check_file` before its work, then writes)."""
    p = Path(path)
    st = _lstat(p)
    if st is not None and stat.S_ISLNK(st.st_mode) and not force:
        check_file(p, force=False, what=what)  # raises: a link
    if st is not None and not force:
        check_file(p, force=False, what=what)  # raises: it exists
    if st is not None and not (stat.S_ISREG(st.st_mode) or stat.S_ISLNK(st.st_mode)):
        check_file(p, force=True, what=what)  # raises: a folder or device
    if isinstance(data, (bytes, bytearray, memoryview)):
        payload = bytes(data)

        def write(fh: IO[bytes]) -> None:
            fh.write(payload)

        return atomic_write(p, write)
    return atomic_write(p, data)


def save_figure(fig: Figure, path: str | Path, **kwargs: Any) -> Path:
    """Save the matplotlib figure ``fig`` to ``path`` through :func:`write_file` (the format
    from the suffix; ``kwargs`` go to ``savefig``)."""
    buf = io.BytesIO()
    fmt = Path(path).suffix.lstrip(".") or "png"
    fig.savefig(buf, format=fmt, **kwargs)
    return write_file(path, buf.getvalue())


def marked_as(folder: str | Path) -> str | None:
    """The experiment whose marker :data:`MARKER` is in ``folder`` (None: no marker)."""
    p = Path(folder) / MARKER
    st = _lstat(p)
    if st is None:
        return None
    bad = UsageError(
        f"{str(p)!r} is not a sigmapi marker file; move it away or give another output folder"
    )
    if not stat.S_ISREG(st.st_mode) or st.st_size > _MAX_MARKER:
        raise bad
    try:
        data = json.loads(p.read_bytes().decode("utf-8"))
    except (OSError, UnicodeError, ValueError):
        raise bad from None
    if not isinstance(data, dict) or not isinstance(data.get("experiment"), str):
        raise bad
    return str(data["experiment"])


def claim_folder(
    folder: str | Path, experiment: str, *, force: bool, owns: Collection[str] = ()
) -> Path:
    """Make the existing ``folder`` the output folder of ``experiment``, before its work.

    A folder marked for ``experiment`` is its own (what is in it may be replaced); one marked
    for another experiment is refused; an unmarked one must be empty but for the lock, the
    names in ``owns`` (files the experiment checks itself, e.g. a sweep's table) and
    temporary files of sigmapi's writes, unless ``force``. Then the marker is written.
    """
    out = Path(folder)
    owner = marked_as(out)
    where = f"--out folder {str(out)!r}"
    if owner is not None and owner != experiment:
        raise UsageError(
            f"{where} holds a run of the experiment {owner!r} (its marker "
            f"{MARKER}), not of {experiment!r}; give another --out (or move that "
            "run away, marker included)"
        )
    if owner is None:
        pattern = temp_pattern()
        foreign = sorted(
            e.name
            for e in out.iterdir()
            if e.name not in (LOCK_NAME, *owns) and not re.fullmatch(pattern, e.name)
        )
        if foreign and not force:
            shown = ", ".join(foreign[:5]) + (
                f" and {len(foreign) - 5} more" if foreign[5:] else ""
            )
            raise UsageError(
                f"{where} is not empty; pass --force to write into it, or give another --out "
                f"(it holds no sigmapi {experiment} run, but {shown}: left as they are)"
            )
        write_file(out / MARKER, (json.dumps({"experiment": experiment}) + "\n").encode())
    return out


def save_captioned(fig: Figure, path: str | Path, caption: str, **kwargs: Any) -> Path:
    """Save ``fig`` to ``path`` (:func:`save_figure`) and its caption beside it, ``path`` with
    the suffix ``.txt`` (one line of text); returns the figure's path."""
    out = save_figure(fig, path, **kwargs)
    write_file(Path(path).with_suffix(".txt"), (caption + "\n").encode("utf-8"))
    return out


def save_gif(
    frames: Sequence[NDArray[np.uint8]], path: str | Path, *, fps: int, force: bool = True
) -> Path:
    """Save ``frames`` (``(H, W, 3)`` uint8 arrays) as an animated GIF at ``path`` through
    :func:`write_file` (atomic, never through a link); Pillow comes with matplotlib."""
    from PIL import Image

    images = [Image.fromarray(f) for f in frames]

    def write(fh: IO[bytes]) -> None:
        images[0].save(
            fh, format="GIF", save_all=True, append_images=images[1:], duration=1000 // fps, loop=0
        )

    return write_file(path, write, force=force, what="--render file")
