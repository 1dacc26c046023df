"""Argument checks shared by every module, so that every message has one form.

``"<name> must be <constraint>, got <value>; <fix>"``: the parameter, the constraint, the
value received and (where one helps) the fix, e.g. ``"iterations must be an int >= 1, got 0;
the paper runs 300000"``. Each check returns the value in its canonical type (``int``,
``float``, ``bool``, ``tuple``) and raises :class:`~sigmapi.errors.ConfigError` (a
``ValueError``), or the error class given as ``error``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Collection, Iterable, Mapping
from typing import TYPE_CHECKING, Any, TypeGuard, TypeVar, cast

import numpy as np

from sigmapi.errors import ConfigError

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

__all__ = [
    "KINDS",
    "MAX_WIDTH",
    "Bounds",
    "boolean",
    "bounded",
    "check_fields",
    "choice",
    "fail",
    "integer",
    "is_int",
    "number",
    "positive",
    "shape",
    "width",
]

T = TypeVar("T")

MAX_UNITS = 2**32
"""Most units a shape may have (a map or a code): far beyond any memory, so that sizes stay
within int64 and reach the memory checks as numbers."""


def fail(
    name: str, constraint: str, value: object, fix: str = "", error: type[Exception] = ConfigError
) -> Exception:
    """The error ``"<name> must be <constraint>, got <value>; <fix>"`` (to ``raise``)."""
    tail = f"; {fix}" if fix else ""
    return error(f"{name} must be {constraint}, got {value!r}{tail}")


def is_int(value: object) -> TypeGuard[int | np.integer[Any]]:
    """Whether ``value`` is an int (Python or NumPy), not a bool."""
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def _is_real(value: object) -> TypeGuard[float | np.number[Any]]:
    return (
        isinstance(value, (int, float, np.integer, np.floating))
        and not isinstance(value, (bool, np.bool_))
        and math.isfinite(float(value))
    )


def _short(v: float | None) -> str | None:
    """A bound as written by a person: 0 for 0.0, 1e+15 for 1000000000000000.0."""
    if v is None:
        return None
    if isinstance(v, float) and v.is_integer() and abs(v) < 1e6:
        return str(int(v))
    return f"{v:g}" if isinstance(v, float) else str(v)


def _range(
    kind: str, lo: float | None, hi: float | None, lo_open: bool = False, hi_open: bool = False
) -> str:
    """``"an int >= 1"``, ``"a number in (0, 1]"``, ``"a finite number > 0"``, ..."""
    low, high = _short(lo), _short(hi)
    if low is not None and high is not None:
        left, right = "(" if lo_open else "[", ")" if hi_open else "]"
        return f"{kind} in {left}{low}, {high}{right}"
    if kind == "a number":
        kind = "a finite number"
    if low is not None:
        return f"{kind} {'>' if lo_open else '>='} {low}"
    if high is not None:
        return f"{kind} {'<' if hi_open else '<='} {high}"
    return kind


def integer(
    name: str,
    value: object,
    lo: int | None = None,
    hi: int | None = None,
    *,
    fix: str = "",
    error: type[Exception] = ConfigError,
) -> int:
    """``value`` as an int in ``[lo, hi]`` (either bound may be None); bools are refused."""
    if not (is_int(value) and (lo is None or value >= lo) and (hi is None or value <= hi)):
        raise fail(name, _range("an int", lo, hi), value, fix, error)
    return int(value)


def number(
    name: str,
    value: object,
    lo: float | None = None,
    hi: float | None = None,
    *,
    lo_open: bool = False,
    hi_open: bool = False,
    fix: str = "",
    error: type[Exception] = ConfigError,
) -> float:
    """``value`` as a finite float in the interval from ``lo`` to ``hi`` (open ends optional)."""
    if _is_real(value):
        v = float(value)
        if (lo is None or (v > lo if lo_open else v >= lo)) and (
            hi is None or (v < hi if hi_open else v <= hi)
        ):
            return v
    raise fail(name, _range("a number", lo, hi, lo_open, hi_open), value, fix, error)


MAX_WIDTH = 1e6
"""Widest hill or neighbourhood (grid units) any width may be: far wider than any grid, so a
code or neighbourhood is flat long before it; ``width**2`` of a width near 1e154 would
overflow."""


def width(
    name: str,
    value: object,
    lo: float = 0.0,
    *,
    lo_open: bool = False,
    fix: str = "",
    error: type[Exception] = ConfigError,
) -> float:
    """``value`` as a finite float above ``lo`` (as :func:`number` says it) and at most
    :data:`MAX_WIDTH`."""
    v = number(name, value, lo, lo_open=lo_open, fix=fix, error=error)
    if v > MAX_WIDTH:
        raise fail(
            name, f"<= {MAX_WIDTH:g} (a width past any grid: flat already)", value, fix, error
        )
    return v


def positive(
    name: str, value: object, *, fix: str = "", error: type[Exception] = ConfigError
) -> float:
    """``value`` as a finite float > 0."""
    return number(name, value, 0.0, lo_open=True, fix=fix, error=error)


def boolean(
    name: str, value: object, *, fix: str = "", error: type[Exception] = ConfigError
) -> bool:
    """``value`` if it is a bool (no truthiness: ``"yes"`` and ``1`` are refused)."""
    if not isinstance(value, bool):
        raise fail(name, "true or false", value, fix, error)
    return value


def choice(
    name: str,
    value: T,
    options: Iterable[T],
    *,
    fix: str = "",
    error: type[Exception] = ConfigError,
) -> T:
    """``value`` if it is one of ``options``."""
    opts = tuple(options)
    if value not in opts:
        raise fail(name, f"one of {opts}", value, fix, error)
    return value


def shape(
    name: str, value: object, fix: str = "", error: type[Exception] = ConfigError
) -> tuple[int, ...]:
    """``value`` (an int or a sequence of ints) as a non-empty tuple of positive ints."""
    fix = fix or f"use e.g. {name}=(15,) for 1-D or {name}=(15, 15) for 2-D"
    constraint = "a positive int or a non-empty tuple of positive ints"
    items = (value,) if is_int(value) else cast("Iterable[object]", value)  # else TypeError
    try:
        out = tuple(items)
    except TypeError:
        raise fail(name, constraint, value, fix, error) from None
    sizes = tuple(int(s) for s in out if is_int(s) and s >= 1)
    if not out or len(sizes) != len(out):
        raise fail(name, constraint, value, fix, error)
    if math.prod(sizes) > MAX_UNITS:
        raise fail(
            name, f"a shape of at most {MAX_UNITS:,} units (2**32) in all", value, fix, error
        )
    return sizes


# ------------------------------------------------------------------ declarative bounds


KINDS = ("int", "number", "width", "bool", "choice", "ints", "numbers")
"""The kinds of :class:`Bounds`: an int, a finite float, a width (:func:`width`), a bool
(:func:`boolean`), one of given options (:func:`choice`), a tuple of ints or of finite floats
(each within the bounds, at most :attr:`Bounds.count` of them)."""

MAX_ITEMS = 100
"""Most values a tuple field (kinds ``"ints"`` and ``"numbers"``) takes unless it says."""


@dataclasses.dataclass(frozen=True)
class Bounds:
    """The bounds of a config field, declared beside it (:func:`bounded`), checked by
    :func:`check_fields` and shown by ``--help`` (:meth:`describe`)."""

    kind: str
    """One of :data:`KINDS`."""
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    fix: str = ""
    """The fix the error names (e.g. ``"e.g. 600"``)."""
    options: Collection[object] = ()
    """The values a ``"choice"`` field takes (read when checked: a registry may grow)."""
    none: bool = False
    """Whether None is a value too (e.g. a seed: None draws fresh entropy)."""
    count: int = MAX_ITEMS
    """Most values of a tuple (kinds ``"ints"`` and ``"numbers"``)."""
    why: str = ""
    """Why a number has no upper bound (``hi`` None), where it has none: a size that drives
    the work has one (tests/cli/test_hostile_round5.py walks every experiment's config)."""
    exact: bool = False
    """A tuple takes exactly :attr:`count` values, not at most (e.g. a 2-D map's shape)."""

    def describe(self) -> str:
        """``"an int >= 1"``, ``"a number in (0, 1]"``, ``"one of 'a', 'b'"``, ..."""
        if self.kind == "int":
            text = _range("an int", self.lo, self.hi)
        elif self.kind == "number":
            text = _range("a number", self.lo, self.hi, self.lo_open, self.hi_open)
        elif self.kind == "width":
            text = f"{_range('a number', self.lo, None, self.lo_open)}, <= {MAX_WIDTH:g}"
        elif self.kind == "bool":
            text = "true or false"
        elif self.kind in ("ints", "numbers"):
            kind = "an int" if self.kind == "ints" else "a number"
            one = _range(kind, self.lo, self.hi, self.lo_open, self.hi_open)
            many = "exactly" if self.exact else "up to"
            text = f"{many} {self.count} values, each {one}"
        else:
            text = "one of " + ", ".join(repr(o) for o in self.options)
        text = f"{text}, or None" if self.none else text
        return f"{text} ({self.why})" if self.why else text

    def check(self, name: str, value: object) -> object:
        """``value`` checked (:func:`integer`, :func:`number`, :func:`width`,
        :func:`boolean` or :func:`choice`), in its canonical type."""
        if value is None and self.none:
            return None
        if self.kind == "int":
            lo = None if self.lo is None else int(self.lo)
            hi = None if self.hi is None else int(self.hi)
            return integer(name, value, lo, hi, fix=self.fix)
        if self.kind == "width":
            return width(name, value, self.lo or 0.0, lo_open=self.lo_open, fix=self.fix)
        if self.kind == "bool":
            return boolean(name, value, fix=self.fix)
        if self.kind == "choice":
            return choice(name, value, self.options, fix=self.fix)
        if self.kind in ("ints", "numbers"):
            return self._values(name, value)
        return number(
            name, value, self.lo, self.hi, lo_open=self.lo_open, hi_open=self.hi_open, fix=self.fix
        )

    def _values(self, name: str, value: object) -> tuple[object, ...]:
        """A tuple field's values, each checked as :attr:`kind` says."""
        if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, Iterable):
            raise fail(name, self.describe(), value, self.fix)
        items = tuple(value)
        if len(items) > self.count or (self.exact and len(items) != self.count):
            shown = f"{len(items):,} value" + ("" if len(items) == 1 else "s")
            many = "exactly" if self.exact else "at most"
            raise fail(name, f"{many} {self.count} values", shown, self.fix)
        kind = "int" if self.kind == "ints" else "number"
        one = Bounds(kind, self.lo, self.hi, self.lo_open, self.hi_open, self.fix)
        return tuple(one.check(name, v) for v in items)


def bounded(
    kind: str,
    lo: float | None = None,
    hi: float | None = None,
    *,
    lo_open: bool = False,
    hi_open: bool = False,
    fix: str = "",
    options: Collection[object] = (),
    none: bool = False,
    count: int = MAX_ITEMS,
    why: str = "",
    exact: bool = False,
    **more: object,
) -> Mapping[str, object]:
    """Field metadata declaring :class:`Bounds`: ``episodes: int = field(default=600,
    metadata=bounded("int", 1))``, ``relation: str = field(default="mean",
    metadata=bounded("choice", options=RELATIONS))``; ``more`` is further metadata (e.g.
    ``sep=","``)."""
    if kind not in KINDS:
        raise ValueError(f"bounds are of a kind in {KINDS}, got {kind!r}")
    return {
        "bounds": Bounds(kind, lo, hi, lo_open, hi_open, fix, options, none, count, why, exact),
        **more,
    }


def check_fields(obj: DataclassInstance) -> None:
    """Check every field of the frozen dataclass ``obj`` that declares :class:`Bounds` (in the
    order of the fields) and store its canonical value: the one validator of declared bounds."""
    for f in dataclasses.fields(obj):
        b = f.metadata.get("bounds")
        if b is not None:
            object.__setattr__(obj, f.name, b.check(f.name, getattr(obj, f.name)))
