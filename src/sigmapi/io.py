"""Model files: NumPy ``.npz`` archives read with ``allow_pickle=False``, written atomically.

This module reads and writes verified archives; it knows the file layout, not the model:
:meth:`sigmapi.SigmaPiSOM.to_arrays` and :meth:`~sigmapi.SigmaPiSOM.from_arrays` turn a
model into the header and arrays below and back.

Layout (format ``sigmapi-model``, version 1): two members,

- ``header``: a uint8 array holding UTF-8 JSON: format, version, the resolved config, the
  iteration count ``t``, the seed entropy of the random streams, the weight dtype and shape,
  and the SHA-256 of the weight bytes;
- ``weights``: the float weights ``(n_units, n_x, n_y)``;
- ``state_<name>``: extra arrays of the backend that wrote the file (the fast kernel's raw
  float32 weights and per-unit scale factors), so that a model continues bit for bit on the
  same backend. A different backend starts from ``weights``.

The file is written to a temporary file in the same folder, flushed, fsync'ed and renamed over
the target, so a reader sees the old file or the new one, never half of one. Loading checks
everything it reads (format, version, keys, dtype, shape, finiteness, checksum) and raises
:class:`~sigmapi.errors.ModelFileError` naming the problem; no object is ever unpickled.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi.errors import ModelFileError

__all__ = ["FORMAT", "VERSION", "atomic_write_bytes", "read_archive", "read_model", "write_model"]

FORMAT = "sigmapi-model"
VERSION = 1
_MAX_HEADER = 1 << 20


def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically: temp file in the same folder, fsync, rename."""
    target = Path(path)
    folder = target.parent if str(target.parent) else Path(".")
    if not folder.is_dir():
        raise ModelFileError(f"cannot write {str(target)!r}: folder {str(folder)!r} does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
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


def digest(weights: NDArray[Any]) -> str:
    """SHA-256 of the weight bytes in C order."""
    return hashlib.sha256(np.ascontiguousarray(weights).tobytes()).hexdigest()


def header_digest(header: dict[str, Any]) -> str:
    """SHA-256 of the canonical JSON of ``header`` without its own ``header_sha256`` entry."""
    body = {k: v for k, v in header.items() if k != "header_sha256"}
    return hashlib.sha256(json.dumps(body, sort_keys=True).encode("utf-8")).hexdigest()


def encode_archive(header: dict[str, Any], arrays: dict[str, NDArray[Any]]) -> bytes:
    """The bytes of an ``.npz`` archive holding ``header`` as JSON plus ``arrays``."""
    import io as _io

    buf = _io.BytesIO()
    head = np.frombuffer(json.dumps(header, sort_keys=True).encode("utf-8"), dtype=np.uint8)
    np.savez(buf, header=head, **arrays)  # type: ignore[arg-type]
    return buf.getvalue()


def read_archive(
    path: str | Path, kind: str = FORMAT
) -> tuple[dict[str, Any], dict[str, NDArray[Any]]]:
    """Read and sanity-check an archive; returns (header, arrays). Never unpickles."""
    p = Path(path)
    if not p.exists():
        raise ModelFileError(f"model file {str(p)!r} does not exist; check the path")
    if not p.is_file():
        raise ModelFileError(f"model file {str(p)!r} is not a regular file")
    try:
        with open(p, "rb") as fh:
            magic = fh.read(4)
    except OSError as exc:
        raise ModelFileError(f"model file {str(p)!r} cannot be read: {exc}") from None
    if magic != b"PK\x03\x04":
        raise ModelFileError(f"{str(p)!r} is not a sigmapi model file (not an .npz archive)")
    try:
        with open(p, "rb") as fh, np.load(fh, allow_pickle=False) as npz:
            names = set(npz.files)
            if "header" not in names:
                raise ModelFileError(f"{str(p)!r} has no header: not a sigmapi model file")
            raw = npz["header"]
            if raw.dtype != np.uint8 or raw.ndim != 1 or raw.size > _MAX_HEADER:
                raise ModelFileError(f"{str(p)!r}: header must be a 1-D uint8 array of JSON")
            try:
                header = json.loads(raw.tobytes().decode("utf-8"))
            except (UnicodeDecodeError, json.JSONDecodeError) as exc:
                raise ModelFileError(f"{str(p)!r}: header is not valid JSON ({exc})") from None
            if not isinstance(header, dict):
                raise ModelFileError(f"{str(p)!r}: header must be a JSON object")
            arrays = {n: npz[n] for n in sorted(names - {"header"})}
    except ModelFileError:
        raise
    except ValueError as exc:
        if "pickle" in str(exc).lower():
            raise ModelFileError(
                f"{str(p)!r} holds a pickled object; refused (sigmapi files never contain code)"
            ) from None
        raise ModelFileError(f"{str(p)!r} is damaged or not a sigmapi model file ({exc})") from None
    except (OSError, EOFError, zipfile.BadZipFile, KeyError, RuntimeError) as exc:
        raise ModelFileError(f"{str(p)!r} is damaged or not a sigmapi model file ({exc})") from None
    if header.get("format") != kind:
        raise ModelFileError(f"{str(p)!r}: format is {header.get('format')!r}, expected {kind!r}")
    if header.get("version") != VERSION:
        raise ModelFileError(
            f"{str(p)!r}: file version {header.get('version')!r} is not supported by this "
            f"sigmapi (reads version {VERSION}); use the sigmapi release that wrote it"
        )
    return header, arrays


def write_model(path: str | Path, header: dict[str, Any], arrays: dict[str, NDArray[Any]]) -> Path:
    """Write a model's ``header`` and ``arrays`` atomically to ``path``, with checksums.

    ``arrays`` holds ``"weights"`` and optional ``"state_<name>"`` arrays (see
    :meth:`sigmapi.SigmaPiSOM.to_arrays`); the file gets the format, version, the weight
    dtype, shape and SHA-256, the SHA-256 of each state array and of the header itself.
    """
    w = np.ascontiguousarray(arrays["weights"])
    extra = {k: np.ascontiguousarray(v) for k, v in arrays.items() if k != "weights"}
    full = {
        "format": FORMAT,
        "version": VERSION,
        **header,
        "dtype": str(w.dtype),
        "shape": list(w.shape),
        "sha256": digest(w),
        "state_sha256": {k[len("state_") :]: digest(v) for k, v in extra.items()},
    }
    full["header_sha256"] = header_digest(full)
    return atomic_write_bytes(path, encode_archive(full, {"weights": w, **extra}))


def read_model(path: str | Path) -> tuple[dict[str, Any], dict[str, NDArray[Any]]]:
    """Read and verify a model file written by :func:`write_model`; returns (header, arrays).

    Checks the format, version, header keys and checksum, the weights (float, the dtype and
    shape the header states, finite, checksum) and each state array (float, finite,
    checksum); raises :class:`~sigmapi.errors.ModelFileError` naming the problem. Whether
    the arrays make a model is :meth:`sigmapi.SigmaPiSOM.from_arrays`'s to check.
    """
    header, arrays = read_archive(path)
    name = str(path)
    for key in ("config", "t", "seed_entropy", "dtype", "shape", "sha256", "header_sha256"):
        if key not in header:
            raise ModelFileError(f"{name!r}: header lacks {key!r}; the file is damaged")
    if header_digest(header) != header["header_sha256"]:
        raise ModelFileError(f"{name!r}: header checksum mismatch; the file is damaged")
    state = {k[len("state_") :]: v for k, v in arrays.items() if k.startswith("state_")}
    if "weights" not in arrays or set(arrays) - {"weights"} - {f"state_{k}" for k in state}:
        raise ModelFileError(
            f"{name!r}: expected an array 'weights' and optional 'state_*' arrays, "
            f"found {sorted(arrays)}"
        )
    w = arrays["weights"]
    if w.dtype.kind != "f" or str(w.dtype) != header["dtype"]:
        raise ModelFileError(
            f"{name!r}: weights have dtype {w.dtype}, header says {header['dtype']!r}"
        )
    if list(w.shape) != header["shape"]:
        raise ModelFileError(
            f"{name!r}: weights have shape {tuple(w.shape)}, header says {header['shape']}"
        )
    if not np.all(np.isfinite(w)):
        raise ModelFileError(f"{name!r}: weights hold NaN or inf values; the file is damaged")
    if digest(w) != header["sha256"]:
        raise ModelFileError(f"{name!r}: weight checksum mismatch; the file is damaged")
    sums = header.get("state_sha256", {})
    if not isinstance(sums, dict) or set(sums) != set(state):
        raise ModelFileError(f"{name!r}: backend state arrays do not match the header")
    for k, v in state.items():
        if v.dtype.kind != "f" or not np.all(np.isfinite(v)) or digest(v) != sums[k]:
            raise ModelFileError(f"{name!r}: backend state array {k!r} is damaged")
    return header, arrays
