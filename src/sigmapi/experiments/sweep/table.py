"""The table of a sweep, ``DIR/results.csv``: run identities, a strict reader, appends.

Every row names its run twice: ``run_id``, the grid values and the seed a person reads
(``{"code_width": 0.5, "seed": 0}``), and ``run_key``, a digest of everything that determines
the run (:func:`run_key`: the resolved config, whatever preset, ``[set]`` or grid put there,
the seed, the evaluation's ``n_test`` and the model format of this sigmapi). A resumed sweep
keeps only the rows whose ``run_key`` is one of its runs; a table that holds runs of another
spec is refused (:func:`open_table`) unless the caller adds to it on purpose, and a file that
is no sweep table, or a damaged one, is refused before anything is written.

The table is append-only: the header is written once (atomically), then one row per finished
run is appended with a single ``write``, so a killed sweep loses only the runs in flight and
``n`` runs cost ``O(n)`` bytes of writing. A run that is run again (a failed run with
``retry_failed``) appends a new row; the last row of a ``run_key`` counts.
"""

from __future__ import annotations

import csv
import dataclasses
import hashlib
import io
import json
import os
import stat
from collections.abc import Collection, Sequence
from pathlib import Path

from sigmapi.errors import ConfigError
from sigmapi.io import FORMAT, VERSION, atomic_write_bytes
from sigmapi.metrics import Metrics

RESULTS = "results.csv"
"""The sweep's table in its output folder."""

METRIC_COLUMNS = tuple(f.name for f in dataclasses.fields(Metrics) if f.name != "circular")
"""The metric columns of every sweep; a sweep of angles adds the circular keys."""

REQUIRED = ("run_id", "run_key", "seed", "status", "error", *METRIC_COLUMNS)
"""Columns every sweep table has."""

MAX_FIELD = 1 << 16
"""Longest field (characters) a table of sigmapi's may hold; longer means damage."""

MAX_ROWS = 200_000
"""Most rows a table read may have: twenty specs of the most runs one names (``--add``)."""

MAX_TABLE = 128 << 20
"""Largest table (bytes) read: ten times a table of the most runs a spec names, with room for
``--add``; a larger file is refused from its size, before it is read."""

_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)


def _check_plain(p: Path) -> os.stat_result | None:
    """``p``'s lstat (None: there is none), refused if it is a link, not a file, or a file
    with other names (hard links: two folders would append to one table)."""
    try:
        st = p.lstat()
    except FileNotFoundError:
        return None
    if stat.S_ISLNK(st.st_mode):
        raise ConfigError(
            f"sweep table {str(p)!r} is a symbolic link; sigmapi never writes "
            "through one: put the file there, or give a new --out"
        )
    if not stat.S_ISREG(st.st_mode):
        raise ConfigError(
            f"sweep table {str(p)!r} is not a file (a folder?); move it away or give a new --out"
        )
    if st.st_nlink > 1:
        raise ConfigError(
            f"sweep table {str(p)!r} has {st.st_nlink} names (hard links), so "
            "two sweeps could append to it at once; copy it to a file of its own, "
            "or give a new --out"
        )
    if st.st_size > MAX_TABLE:
        raise ConfigError(
            f"sweep table {str(p)!r} holds {st.st_size:,} bytes, over the "
            f"{MAX_TABLE:,} a sweep reads; give a new --out"
        )
    return st


def run_key(config: dict[str, object], seed: int, n_test: int) -> str:
    """The identity of one run: 16 hex digits of a SHA-256 over the resolved ``config`` (a
    :meth:`~sigmapi.SOMConfig.to_dict`, its seed left out), ``seed``, ``n_test`` and the model
    format (name and version) of this sigmapi."""
    data = {
        "config": {k: v for k, v in config.items() if k != "seed"},
        "seed": int(seed),
        "n_test": int(n_test),
        "format": [FORMAT, VERSION],
    }
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), default=repr)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


@dataclasses.dataclass
class Table:
    """A sweep table as read: its columns, the last row of each ``run_key`` (in file order)
    and how many bytes of a torn last line (a write cut short) follow the last full row."""

    columns: list[str]
    rows: dict[str, dict[str, str]]
    torn: int = 0


def _damaged(path: Path, detail: str) -> ConfigError:
    return ConfigError(
        f"sweep table {str(path)!r} is damaged ({detail}); move it away to keep it, then run "
        "the sweep again (its runs start over), or give a new --out"
    )


def typed(value: object) -> object:
    """A value of the table as written (a string) back as a bool, int or float where it is one."""
    if not isinstance(value, str) or value in ("", "nan"):
        return value
    if value in ("True", "False"):
        return value == "True"
    for kind in (int, float):
        try:
            return kind(value)
        except ValueError:
            pass
    return value


def _check_row(path: Path, line: int, row: dict[str, str], metrics: Sequence[str]) -> None:
    status = row["status"]
    if status not in ("ok", "failed"):
        raise _damaged(path, f"line {line}: status must be ok or failed, got {status[:40]!r}")
    key = row["run_key"]
    if len(key) != 16 or any(c not in "0123456789abcdef" for c in key):
        raise _damaged(path, f"line {line}: run_key must be 16 hex digits, got {key[:40]!r}")
    if status == "ok":
        for name in metrics:  # a number (nan too) or a bool
            value = row[name]
            if value != "nan" and isinstance(typed(value), str):
                raise _damaged(
                    path, f"line {line}: an ok run's {name} must be a number, got {value[:40]!r}"
                )


def read_table(path: str | Path) -> Table | None:
    """The sweep table at ``path`` (None if there is none), checked: a file that is no sigmapi
    sweep table, or one damaged anywhere but a torn last line, raises ConfigError."""
    p = Path(path)
    if _check_plain(p) is None:
        return None
    fd = os.open(p, os.O_RDONLY | _NOFOLLOW)
    with os.fdopen(fd, "rb") as fh:
        data = fh.read(MAX_TABLE + 1)
    if data.count(b"\n") > MAX_ROWS + 1:  # counted before any row is parsed: cheap
        raise ConfigError(
            f"sweep table {str(p)!r} holds over {MAX_ROWS:,} rows, more than a "
            "sweep writes; give a new --out"
        )
    end = data.rfind(b"\n") + 1
    torn = len(data) - end
    try:
        text = data[:end].decode("utf-8")
    except UnicodeDecodeError as exc:
        first = data[: data.find(b"\n")].decode("utf-8", "replace").rstrip("\r").split(",")
        if any(c not in first for c in REQUIRED):  # no sweep table's header: garbage
            raise ConfigError(
                f"{str(p)!r} is unreadable as a sigmapi sweep table (not UTF-8 text at byte "
                f"{exc.start}, no sweep table's header); it is left as it is: give a new "
                "--out, or move it away"
            ) from None
        raise _damaged(p, f"not UTF-8 text at byte {exc.start}") from None
    reader = csv.reader(io.StringIO(text, newline=""))
    try:
        header = next(reader, None)
        if header is None and data:  # bytes without one line end: garbage, not a table
            raise ConfigError(
                f"{str(p)!r} is unreadable as a sigmapi sweep table (its {len(data):,} bytes "
                "hold no complete line of text); it is left as it is: give a new --out, or "
                "move it away"
            )
        if header is None:
            raise ConfigError(
                f"{str(p)!r} is empty, not a sigmapi sweep table; remove it or give a new --out"
            )
        missing = [c for c in REQUIRED if c not in header]
        if missing:
            what = (
                "an older sigmapi's sweep table (no run identity)"
                if "run_id" in header
                else "not a sigmapi sweep table"
            )
            raise ConfigError(
                f"{str(p)!r} is {what}: its header lacks {missing[0]!r}; it is "
                "left as it is: give a new --out, or move it away"
            )
        if len(set(header)) != len(header) or any(len(c) > 200 for c in header):
            raise _damaged(p, "line 1: a column named twice or a name too long")
        metrics = [c for c in header if c in METRIC_COLUMNS]
        rows: dict[str, dict[str, str]] = {}
        for fields in reader:
            line = reader.line_num
            if len(fields) != len(header):
                raise _damaged(
                    p, f"line {line}: {len(fields)} fields, the header has {len(header)}"
                )
            if any(len(f) > MAX_FIELD for f in fields):
                raise _damaged(p, f"line {line}: a field of over {MAX_FIELD} characters")
            row = dict(zip(header, fields, strict=True))
            _check_row(p, line, row, metrics)
            rows.pop(row["run_key"], None)  # the last row of a run counts, in file order
            rows[row["run_key"]] = row
    except csv.Error as exc:
        raise _damaged(p, f"line {reader.line_num}: {exc}") from None
    return Table(header, rows, torn)


def _line(columns: Sequence[str], row: dict[str, object]) -> bytes:
    """One row as a line of CSV (a NaN as ``nan``, as csv writes it)."""
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow([row.get(c, "") for c in columns])
    return buf.getvalue().encode("utf-8")


def open_table(
    path: str | Path, columns: list[str], keys: Collection[str], *, add: bool = False
) -> dict[str, dict[str, str]]:
    """Make ``path`` ready for appending rows of ``columns``; the rows already there whose
    ``run_key`` is in ``keys`` (the runs of this spec), by ``run_key``.

    A new table gets its header. An existing one must be a sweep table with these columns
    whose runs are all in ``keys``; one holding runs of another spec is refused unless
    ``add`` (its rows are kept, this spec's are appended after them). Nothing is written
    before these checks pass; a torn last line (a write cut short by a kill) is cut off.
    """
    p = Path(path)
    table = read_table(p)
    if table is None:
        atomic_write_bytes(p, _line(columns, dict(zip(columns, columns, strict=True))))
        return {}
    other = [k for k in table.rows if k not in keys]
    if other and not add:
        raise ConfigError(
            f"{str(p)!r} holds {len(other)} runs of another spec (another preset, [set], grid, "
            "seeds, n_test or sigmapi version); it is left as it is: give a new --out, or pass "
            "--add to add this spec's runs to that table"
        )
    if table.columns != list(columns):
        raise ConfigError(
            f"{str(p)!r} has the columns {','.join(table.columns)[:300]}, this spec's are "
            f"{','.join(columns)[:300]}; it is left as it is: give a new --out"
        )
    try:  # find out now, not after the runs, that the table takes rows
        fd = os.open(p, os.O_WRONLY | os.O_APPEND | _NOFOLLOW)
    except OSError as exc:
        raise ConfigError(
            f"cannot append to sweep table {str(p)!r}: {exc.strerror or exc}; "
            "make it writable, or give a new --out"
        ) from None
    try:
        if table.torn:
            os.ftruncate(fd, os.fstat(fd).st_size - table.torn)
    finally:
        os.close(fd)
    return {k: r for k, r in table.rows.items() if k in keys}


def append_row(path: str | Path, columns: Sequence[str], row: dict[str, object]) -> None:
    """Append one row to the table at ``path`` with one ``write`` (and ``fsync``)."""
    data = _line(columns, row)
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | _NOFOLLOW)
    try:
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view) :]
        os.fsync(fd)
    finally:
        os.close(fd)
