# Over 500 lines: the file layout, its bounded reader and its atomic writer read as one.
"""Model files: ``.npz`` archives read member by member with bounds, written atomically.

This module reads and writes verified archives; it knows the file layout, not the model:
:meth:`sigmapi.SigmaPiSOM.to_arrays` and :meth:`~sigmapi.SigmaPiSOM.from_arrays` turn a
model into the header and arrays below and back.

Layout (format ``sigmapi-model``, version 2): a zip archive (``numpy.load`` opens it) of

- ``header.npy``: a uint8 array holding UTF-8 JSON: format, version, the resolved config, the
  iteration count ``t``, the seed entropy of the random streams, the backend that wrote the
  file, and ``arrays``: the dtype, shape and SHA-256 of every other member; last, the SHA-256
  of the header itself;
- the model's arrays, stored once in the precision of the backend that wrote them: either
  ``weights.npy`` (float64 ``(n_units, n_x, n_y)``, the reference kernel) or the kernel's own
  ``state_<name>.npy`` arrays (the fast kernel's float32 ``raw`` weights, per-unit ``scale``
  and ``sqnorm``), from which the weights follow and which continue the run bit for bit.

Version 1 files (until sigmapi 0.x of November 2026) stored float64 ``weights`` and, for the
fast kernel, its state besides; they still load (the two must agree).

Writing: members are stored (``compress=False``) or deflated, into a temporary file
``.NAME.XXXXXXXX.tmp`` in the target's folder, flushed, fsync'ed, given the target's mode (an
existing file's, else what the umask allows: 0644 under umask 022) and renamed over the
target, so a reader sees the old file or the new one, never half of one. Temporary files of
that pattern left by a killed writer are removed by the next write of the same target.

Reading never trusts a size before checking it: the member names, count and the npy headers
are checked from the zip directory before any data is read; the header member is read with a
1 MiB cap; every other member must have exactly the dtype and shape the header declares, which
the stored config bounds, and its bytes are read into an array of that size in chunks (a
stream that inflates further is refused; one that ends early too). Any damage (a flipped bit
in the zip structure, the npy headers, a deflate or LZMA stream, the data) raises
:class:`~sigmapi.errors.ModelFileError` naming the file; no object is ever unpickled.
"""

from __future__ import annotations

import ast
import hashlib
import json
import lzma
import os
import re
import secrets
import stat
import struct
import threading
import time
import zipfile
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import IO, cast

import numpy as np
from numpy.typing import NDArray

from sigmapi import _memory
from sigmapi.errors import DataError, ModelFileError
from sigmapi.kernels import columns

__all__ = [
    "FORMAT",
    "VERSION",
    "atomic_write",
    "atomic_write_bytes",
    "encode_archive",
    "read_archive",
    "read_model",
    "stale_temps",
    "temp_pattern",
    "write_model",
]

FORMAT = "sigmapi-model"
VERSION = 2
READS = (1, 2)
"""Format versions this sigmapi reads."""
MAX_HEADER = 1 << 20
"""Largest header (JSON bytes) a file may hold; :class:`~sigmapi.SOMConfig` keeps ``extra``
well below it."""
_MAX_MEMBERS = 8
_MEMBER = re.compile(r"^(header|weights|state_[a-z][a-z0-9_]{0,31})\.npy$")
_DESCR = {"<f8": np.float64, "<f4": np.float32, "|u1": np.uint8}
_FLOATS = ("<f8", "<f4")
_CHUNK = 1 << 22
_STALE_S = 60.0
# what a damaged zip, deflate or LZMA stream or npy header can raise inside zipfile and numpy
_DAMAGE = (
    OSError,
    EOFError,
    zipfile.BadZipFile,
    zipfile.LargeZipFile,
    zlib.error,
    lzma.LZMAError,
    struct.error,
    ValueError,
    KeyError,
    IndexError,
    TypeError,
    OverflowError,
    RuntimeError,
    NotImplementedError,
    UnicodeError,
    SyntaxError,
    RecursionError,
    MemoryError,
)


# ---------------------------------------------------------------------------- writing


_umask_lock = threading.Lock()


def _umask() -> int:
    with _umask_lock:  # os.umask can only be read by setting it
        mask = os.umask(0o022)
        os.umask(mask)
    return mask


def temp_pattern(name: str = r"[^/]+") -> str:
    """Regex of the temporary files :func:`atomic_write` makes for targets named ``name``."""
    return rf"\.{name}\.[A-Za-z0-9_]{{8}}\.tmp"


_TEMP_FLAGS = os.O_RDWR | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0)
_TEMP_CHARS = "abcdefghijklmnopqrstuvwxyz0123456789_"


def temp_name(folder: Path, name: str) -> Path:
    """A fresh temporary file name ``folder/.NAME.XXXXXXXX.tmp`` (:func:`temp_pattern`), not yet
    made. A caller creates it with ``O_EXCL`` inside the ``try`` that removes it: unlike
    ``tempfile.mkstemp``, which makes the file before its name reaches the caller, a signal
    arriving between the two can no longer leave the file behind."""
    token = "".join(secrets.choice(_TEMP_CHARS) for _ in range(8))
    return folder / f".{name}.{token}.tmp"


def stale_temps(folder: Path, name: str, idle_s: float = _STALE_S) -> list[Path]:
    """Temporary files in ``folder`` of writes of targets matching the regex ``name`` (our
    pattern only: ``.NAME.XXXXXXXX.tmp``), regular files not written to for ``idle_s``."""
    pattern = re.compile(rf"^{temp_pattern(name)}$")
    now = time.time()
    found = []
    for p in folder.iterdir():
        if pattern.match(p.name):
            try:
                st = p.lstat()
            except OSError:
                continue
            if stat.S_ISREG(st.st_mode) and now - st.st_mtime > idle_s:
                found.append(p)
    return found


def atomic_write(path: str | Path, write: Callable[[IO[bytes]], None]) -> Path:
    """Call ``write(fh)`` on a temp file in ``path``'s folder, fsync it, rename it to ``path``.

    The file gets the mode of the file it replaces, else ``0o666`` less the umask. A temp file
    is removed if ``write`` raises (SIGTERM reaches here as ``SystemExit`` under the CLI);
    ones that earlier, killed writes of ``path`` left are removed first.
    """
    target = Path(path)
    folder = target.parent if str(target.parent) else Path(".")
    if not folder.is_dir():
        raise ModelFileError(f"cannot write {str(target)!r}: folder {str(folder)!r} does not exist")
    if target.exists() and not target.is_file():  # a device, FIFO or folder: never replace
        raise ModelFileError(
            f"cannot write {str(target)!r}: it exists and is not a regular file; give a file name"
        )
    for old in stale_temps(folder, re.escape(target.name)):
        old.unlink(missing_ok=True)
    try:
        mode = stat.S_IMODE(target.stat().st_mode) if target.is_file() else None
    except OSError:
        mode = None
    tmp = temp_name(folder, target.name)  # named before it exists: see below
    try:
        fd = os.open(tmp, _TEMP_FLAGS, 0o600)
        if hasattr(os, "fchmod"):  # POSIX: made 0600, given the target's mode now
            os.fchmod(fd, mode if mode is not None else 0o666 & ~_umask())
        with os.fdopen(fd, "wb") as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except FileExistsError:  # another file by that name (not ours): left alone
        raise
    except BaseException:  # SIGTERM (SystemExit) between the open and any later line too
        tmp.unlink(missing_ok=True)
        raise
    try:  # make the rename itself durable
        dfd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)
    except OSError:
        pass
    return target


def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (see :func:`atomic_write`)."""

    def write(fh: IO[bytes]) -> None:
        fh.write(data)

    return atomic_write(path, write)


def digest(a: NDArray[np.generic]) -> str:
    """SHA-256 of an array's bytes in C order."""
    return hashlib.sha256(np.ascontiguousarray(a).tobytes()).hexdigest()


def header_digest(header: dict[str, object]) -> str:
    """SHA-256 of the canonical JSON of ``header`` without its own ``header_sha256`` entry."""
    body = {k: v for k, v in header.items() if k != "header_sha256"}
    return hashlib.sha256(json.dumps(body, sort_keys=True).encode("utf-8")).hexdigest()


def _write_archive(
    fh: IO[bytes], header: dict[str, object], arrays: dict[str, NDArray[np.generic]], compress: bool
) -> None:
    head = np.frombuffer(json.dumps(header, sort_keys=True).encode("utf-8"), dtype=np.uint8)
    method = zipfile.ZIP_DEFLATED if compress else zipfile.ZIP_STORED
    with zipfile.ZipFile(fh, "w", compression=method, allowZip64=True) as zf:
        for name, a in {"header": head, **arrays}.items():
            with zf.open(f"{name}.npy", "w", force_zip64=True) as member:
                np.lib.format.write_array(member, np.ascontiguousarray(a), allow_pickle=False)


def encode_archive(
    header: dict[str, object], arrays: dict[str, NDArray[np.generic]], compress: bool = False
) -> bytes:
    """The bytes of an archive holding ``header`` as JSON plus ``arrays`` (as written)."""
    import io as _io

    buf = _io.BytesIO()
    _write_archive(buf, header, arrays, compress)
    return buf.getvalue()


def write_model(
    path: str | Path,
    header: dict[str, object],
    arrays: dict[str, NDArray[np.generic]],
    compress: bool = False,
) -> Path:
    """Write a model's ``header`` and ``arrays`` atomically to ``path``, with checksums.

    ``arrays`` holds ``"weights"`` or ``"state_<name>"`` arrays (see
    :meth:`sigmapi.SigmaPiSOM.to_arrays`); the file gets the format, version, the dtype,
    shape and SHA-256 of each array and the SHA-256 of the header itself. ``compress``
    deflates the members (smaller, slower to write and read).
    """
    data = {k: np.ascontiguousarray(v) for k, v in arrays.items()}
    for k, v in data.items():
        if not _MEMBER.match(f"{k}.npy") or k == "header" or v.dtype.str not in _FLOATS:
            raise DataError(
                f"array {k!r} must be float64 or float32, named 'weights' or 'state_<name>' "
                f"(lower case), to be stored in a model file, got dtype {v.dtype}; a backend's "
                "file_arrays must return such arrays"
            )
    full = {
        "format": FORMAT,
        "version": VERSION,
        **header,
        "arrays": {
            k: {"dtype": v.dtype.str, "shape": list(v.shape), "sha256": digest(v)}
            for k, v in data.items()
        },
    }
    full["header_sha256"] = header_digest(full)
    return atomic_write(path, lambda fh: _write_archive(fh, full, data, compress))


# ---------------------------------------------------------------------------- reading


def _damaged(name: str, detail: object) -> ModelFileError:
    """The error of file ``name`` whose archive structure is damaged, ``detail`` saying where."""
    return ModelFileError(f"{name!r} is damaged or not a sigmapi model file ({detail})")


def _bad_header(name: str, detail: object) -> ModelFileError:
    """The error of file ``name`` whose header does not describe a model's arrays."""
    return ModelFileError(f"{name!r}: header is damaged ({detail})")


def _npy_header(stream: IO[bytes], name: str) -> tuple[str, tuple[int, ...], int]:
    """(descr, shape, bytes of the npy header) of an npy stream of file ``name``; raises
    :class:`~sigmapi.errors.ModelFileError` if it is damaged."""
    pre = stream.read(8)
    if len(pre) != 8 or pre[:6] != b"\x93NUMPY" or pre[6] not in (1, 2, 3) or pre[7] != 0:
        raise _damaged(name, "not an npy array")
    fmt = "<H" if pre[6] == 1 else "<I"
    raw_len = stream.read(struct.calcsize(fmt))
    if len(raw_len) != struct.calcsize(fmt):
        raise _damaged(name, "npy header is cut short")
    (n,) = struct.unpack(fmt, raw_len)
    if n > 4096:
        raise _damaged(name, f"npy header of {n} bytes (at most 4096)")
    text = stream.read(n)
    if len(text) != n:
        raise _damaged(name, "npy header is cut short")
    d = ast.literal_eval(text.decode("latin1" if pre[6] < 3 else "utf-8").strip())
    if not isinstance(d, dict) or set(d) != {"descr", "fortran_order", "shape"}:
        raise _damaged(name, "npy header is not a dict of descr, fortran_order, shape")
    descr, shape = d["descr"], d["shape"]
    if d["fortran_order"] is not False or descr not in _DESCR:
        raise _damaged(
            name, f"npy array of dtype {descr!r} / fortran order (not what sigmapi writes)"
        )
    if not isinstance(shape, tuple) or not all(type(s) is int and s >= 0 for s in shape):
        raise _damaged(name, f"npy shape {shape!r} is not a tuple of ints >= 0")
    return descr, shape, 8 + len(raw_len) + n


def _read_member(
    zf: zipfile.ZipFile,
    info: zipfile.ZipInfo,
    descrs: tuple[str, ...],
    shape: tuple[int, ...] | None,
    name: str,
    max_bytes: int = MAX_HEADER,
) -> NDArray[np.generic]:
    """One member of file ``name`` as an array, checked against ``descrs`` and ``shape``
    (None: 1-D, at most ``max_bytes``) before its data is read; read in chunks into an array
    of that size. Raises :class:`~sigmapi.errors.ModelFileError` if it does not fit."""
    member = info.filename
    with zf.open(info) as stream:
        descr, found, pre = _npy_header(stream, name)
        if descr not in descrs:
            raise _damaged(name, f"{member} has dtype {descr!r}, expected one of {descrs}")
        itemsize = np.dtype(_DESCR[descr]).itemsize
        if shape is None:
            if len(found) != 1 or found[0] * itemsize > max_bytes:
                raise _damaged(name, f"{member} must be 1-D of at most {max_bytes} bytes")
        elif found != shape:
            raise _damaged(name, f"{member} has shape {found}, the header declares {shape}")
        nbytes = int(np.prod(found, dtype=object)) * itemsize
        if info.file_size != pre + nbytes:
            raise _damaged(
                name,
                f"{member} holds {info.file_size} bytes, its npy header declares {pre + nbytes}",
            )
        out = np.empty(found, dtype=_DESCR[descr])
        view = memoryview(out.reshape(-1).view(np.uint8))  # type: ignore[arg-type]
        done = 0
        while done < nbytes:
            chunk = stream.read(min(_CHUNK, nbytes - done))
            if not chunk:
                raise _damaged(name, f"{member} ends after {done} of {nbytes} bytes")
            view[done : done + len(chunk)] = chunk
            done += len(chunk)
        if stream.read(1):  # also makes zipfile check the member's CRC
            raise _damaged(name, f"{member} holds more than its npy header declares")
    return out


def _dims(header: dict[str, object], name: str) -> tuple[int, int, int]:
    """(n_units, n_x, n_y) of the header's config: what bounds every array's size."""
    cfg = header.get("config")
    if not isinstance(cfg, dict):
        raise _bad_header(name, "the header has no config table")
    dims = []
    for key in ("map_shape", "x_shape", "y_shape"):
        s = cfg.get(key)
        if not isinstance(s, list) or not s or not all(type(v) is int and v >= 1 for v in s):
            raise _bad_header(name, f"config {key} is not a list of positive ints")
        dims.append(int(np.prod(s, dtype=object)))
    return dims[0], dims[1], dims[2]


Expect = dict[str, tuple[tuple[str, ...], tuple[int, ...]]]


def _declared(header: dict[str, object], source: str) -> Expect:
    """Member name -> (allowed dtypes, shape) that the header of file ``source`` declares,
    bounded by its config; raises :class:`~sigmapi.errors.ModelFileError` if it cannot.

    Version 2 declares every array; version 1 declared the weights, and its state arrays were
    those of one kernel's layout, of fixed shapes (:func:`sigmapi.kernels.columns.
    version1_members`).
    """
    k, nx, ny = _dims(header, source)
    n_weights = k * nx * ny
    if header["version"] == 1:
        out: Expect = {"weights": (_FLOATS, (k, nx, ny))}
        states = header.get("state_sha256")
        if not isinstance(states, dict):
            raise _bad_header(source, "state_sha256 is not a table")
        fixed = columns.version1_members((k, nx, ny), _FLOATS)
        for name in states:
            if name not in fixed:
                raise _bad_header(source, f"unknown version-1 state array {name!r}")
            out[f"state_{name}"] = fixed[name]
        return out
    decl = header.get("arrays")
    if not isinstance(decl, dict) or not decl or len(decl) > _MAX_MEMBERS - 1:
        raise _bad_header(source, "the header's arrays table is missing or too long")
    out = {}
    for name, d in decl.items():
        if not isinstance(name, str) or not _MEMBER.match(f"{name}.npy") or name == "header":
            raise _bad_header(source, f"array name {name!r} is not one sigmapi writes")
        shape = d.get("shape") if isinstance(d, dict) else None
        if not isinstance(shape, list) or not all(type(s) is int and s >= 0 for s in shape):
            raise _bad_header(
                source, f"array {name!r}: declared shape {shape!r} is not a list of ints"
            )
        if d.get("dtype") not in _FLOATS or not isinstance(d.get("sha256"), str):
            raise _bad_header(source, f"array {name!r}: declared dtype or checksum is invalid")
        if int(np.prod(shape, dtype=object)) > n_weights:
            raise _bad_header(
                source,
                f"array {name!r} declares shape {shape}, larger than the config's "
                f"{n_weights} weights",
            )
        out[name] = ((d["dtype"],), tuple(shape))
    if "weights" in out and out["weights"][1] != (k, nx, ny):
        raise _bad_header(
            source, f"weights declare shape {out['weights'][1]}, the config needs {k, nx, ny}"
        )
    return out


def read_archive(
    path: str | Path, kind: str = FORMAT
) -> tuple[dict[str, object], dict[str, NDArray[np.generic]]]:
    """Read and sanity-check an archive with bounds; returns (header, arrays). Never unpickles.

    Checks, before reading data: the zip directory (at most 8 members, names
    ``header``/``weights``/``state_*``, no duplicates, stored, deflated or LZMA), the header
    (at most 1 MiB of JSON; format ``kind`` and a readable version), and that the members are
    exactly the arrays the header declares, the memory they need being available.
    """
    p = Path(path)
    name = str(p)
    if not p.exists():
        raise ModelFileError(f"model file {name!r} does not exist; check the path")
    if not p.is_file():
        raise ModelFileError(f"model file {name!r} is not a regular file")
    try:
        with open(p, "rb") as fh:
            if fh.read(4) != b"PK\x03\x04":
                raise ModelFileError(f"{name!r} is not a sigmapi model file (not an .npz archive)")
            fh.seek(0)
            with zipfile.ZipFile(fh) as zf:
                infos = _members(zf, name)
                head = _read_member(zf, infos["header"], ("|u1",), None, name)
                header = _parse_header(head, name, kind)
                try:
                    declared = _declared(header, name)
                except (KeyError, TypeError) as exc:
                    raise _bad_header(name, exc) from None
                found = set(infos) - {"header"}
                if found != set(declared):
                    raise ModelFileError(
                        f"{name!r}: holds arrays {sorted(found)}, the header declares "
                        f"{sorted(declared)}; the file is damaged"
                    )
                need = sum(
                    int(np.prod(s, dtype=object)) * np.dtype(_DESCR[d[0]]).itemsize
                    for d, s in declared.values()
                )
                _memory.check(
                    need, f"loading {name!r}", "load it on a larger machine", error=ModelFileError
                )
                arrays = {
                    n: _read_member(zf, infos[n], *declared[n], name) for n in sorted(declared)
                }
    except ModelFileError:
        raise
    except _DAMAGE as exc:
        raise _damaged(name, exc) from None
    return header, arrays


def _members(zf: zipfile.ZipFile, name: str) -> dict[str, zipfile.ZipInfo]:
    """The archive's members by array name, checked from the zip directory alone."""
    infos = zf.infolist()
    names = [i.filename for i in infos]
    if len(infos) > _MAX_MEMBERS:
        raise ModelFileError(f"{name!r} holds {len(infos)} members (a model file has at most 8)")
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise ModelFileError(f"{name!r}: member {dup[0]!r} appears twice; the file is damaged")
    for i in infos:
        if not _MEMBER.match(i.filename):
            raise ModelFileError(
                f"{name!r}: member {i.filename!r} is not one a sigmapi model file holds"
            )
        if i.flag_bits & 0x1 or i.compress_type not in (
            zipfile.ZIP_STORED,
            zipfile.ZIP_DEFLATED,
            zipfile.ZIP_LZMA,
        ):
            raise ModelFileError(
                f"{name!r}: member {i.filename!r} is encrypted or compressed with method "
                f"{i.compress_type} (sigmapi reads stored, deflated or LZMA members)"
            )
    if "header.npy" not in names:
        raise ModelFileError(f"{name!r} has no header: not a sigmapi model file")
    return {i.filename[: -len(".npy")]: i for i in infos}


def _parse_header(raw: NDArray[np.generic], name: str, kind: str) -> dict[str, object]:
    try:
        header = json.loads(raw.tobytes().decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise ModelFileError(f"{name!r}: header is not valid JSON ({exc})") from None
    if not isinstance(header, dict):
        raise ModelFileError(f"{name!r}: header must be a JSON object")
    if header.get("format") != kind:
        raise ModelFileError(f"{name!r}: format is {header.get('format')!r}, expected {kind!r}")
    if header.get("version") not in READS or type(header.get("version")) is not int:
        raise ModelFileError(
            f"{name!r}: file version {header.get('version')!r} is not supported by this "
            f"sigmapi (reads versions {', '.join(map(str, READS))}); use the sigmapi release "
            "that wrote it"
        )
    for key in ("config", "t", "seed_entropy", "header_sha256"):
        if key not in header:
            raise ModelFileError(f"{name!r}: header lacks {key!r}; the file is damaged")
    if header_digest(header) != header["header_sha256"]:
        raise ModelFileError(f"{name!r}: header checksum mismatch; the file is damaged")
    return header


def read_model(path: str | Path) -> tuple[dict[str, object], dict[str, NDArray[np.generic]]]:
    """Read and verify a model file written by :func:`write_model`; returns (header, arrays).

    Checks the format, version, header checksum, that the members are the arrays the header
    declares (dtype and shape), each array's checksum and that it is finite; raises
    :class:`~sigmapi.errors.ModelFileError` naming the problem. Whether the arrays make a
    model is :meth:`sigmapi.SigmaPiSOM.from_arrays`'s to check. Version-1 headers are
    returned with an ``arrays`` table like version 2's.
    """
    header, arrays = read_archive(path)
    name = str(path)
    # read_archive checked the tables (_declared): version 1's state sums, version 2's arrays
    if header["version"] == 1:
        states = cast(dict[str, object], header["state_sha256"])
        sums = {"weights": header.get("sha256"), **{f"state_{k}": v for k, v in states.items()}}
        header["arrays"] = {
            k: {"dtype": a.dtype.str, "shape": list(a.shape), "sha256": sums[k]}
            for k, a in arrays.items()
        }
    table = cast(dict[str, dict[str, object]], header["arrays"])
    for k, a in arrays.items():
        if not np.all(np.isfinite(a)):
            raise ModelFileError(f"{name!r}: array {k!r} holds NaN or inf values; damaged")
        if digest(a) != table[k]["sha256"]:
            raise ModelFileError(f"{name!r}: checksum mismatch in array {k!r}; the file is damaged")
    return header, arrays
