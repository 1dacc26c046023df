"""The base of every experiment's result (:class:`Result`), whose keys are defined once, by the
result (the docs read every result file back with it), and console tables (:func:`render`)."""

from __future__ import annotations

import dataclasses
import functools
import importlib
import re
import typing
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, TypeVar

import numpy as np

from sigmapi._outputs import save_captioned
from sigmapi.errors import DataError
from sigmapi.experiments.kit.seeds import check_seeds

if TYPE_CHECKING:
    from matplotlib.figure import Figure

R = TypeVar("R", bound="Result")

JSON = dict[str, Any]
"""A JSON object as it is written or read back: a result's form, a record (values of any JSON
type)."""


def as_object(data: object, what: str = "a result's JSON form") -> Mapping[str, Any]:
    """``data`` if it is a JSON object (a TypeError naming ``what`` if not)."""
    if not isinstance(data, Mapping):
        raise TypeError(f"{what} must be a JSON object, got {type(data).__name__}")
    return data


def summaries(data: object, required: Sequence[str], optional: Sequence[str] = ()) -> JSON:
    """The summary keys of a result's JSON form as written: every one of ``required`` (a
    KeyError naming the first one missing) and those of ``optional`` it holds (keys a newer
    version added)."""
    obj = as_object(data)
    out = {k: obj[k] for k in required}
    out.update({k: obj[k] for k in optional if k in obj})
    return out


def check_records(records: Sequence[object], command: str) -> None:
    """Refuse to draw a result without its ``records`` per seed (one read back from its JSON,
    which holds the pooled numbers, not the records its figures show): one DataError line
    naming the ``command`` that draws them."""
    if not records:
        raise DataError(
            "this result holds no records per seed (read back from its JSON, it has the "
            f"pooled numbers only), and its figures are drawn from those records; run `{command}` "
            "again to draw them"
        )


VC_MARGIN = 0.02
"""Acceptance of a map against its reference (the Sigma-Pi map, the rate map, maps learned
from pairs): its view consistency within this much of the reference's."""


def within_margin(gap: float) -> bool:
    """Whether a view-consistency ``gap`` is within :data:`VC_MARGIN` (a gap of exactly
    -0.02, e.g. 6 test z's of 300, counts: the two rates' float difference may fall a
    rounding error below it)."""
    return gap >= -VC_MARGIN - 1e-9


def margin_case(gaps: Sequence[float], folded: Sequence[bool]) -> JSON:
    """The acceptance of a map against its reference over seeds, from each seed's
    view-consistency ``gaps`` (the map's minus the reference's) and whether its map
    ``folded``: ``vc_gap_median``, ``vc_gap_worst``, the seeds within :data:`VC_MARGIN` and
    ordered (``met``), ``n_seeds`` and ``all_met``."""
    met = [within_margin(g) and not f for g, f in zip(gaps, folded, strict=True)]
    return {
        "vc_gap_median": float(np.median(gaps)),
        "vc_gap_worst": float(min(gaps)),
        "met": int(sum(met)),
        "n_seeds": len(met),
        "all_met": bool(all(met)),
    }


def margin_line(case: Mapping[str, Any], against: str) -> str:
    """A :func:`margin_case` in words: how many seeds are within :data:`VC_MARGIN`
    ``against`` (e.g. ``"of sigma-pi"``) and ordered, the median and worst gap."""
    return (
        f"{case['met']} of {case['n_seeds']} seeds within {VC_MARGIN} {against} and ordered "
        f"(gap median {case['vc_gap_median']:+.3f}, worst {case['vc_gap_worst']:+.3f})"
    )


def tuples(table: Mapping[str, object]) -> JSON:
    """A config's fields as its JSON form holds them, lists as tuples (as the config has them)."""
    return {k: tuple(v) if isinstance(v, list) else v for k, v in table.items()}


def plain(value: object) -> Any:
    """``value`` as JSON types: a dataclass as its ``to_dict()`` (or its fields), a mapping as
    a dict, a tuple or list as a list, a numpy array as nested lists and a numpy scalar as its
    Python value (a NaN or infinity of an array as None); anything else as it is."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        to_dict = getattr(value, "to_dict", None)
        if to_dict is not None:
            return plain(to_dict())
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, Mapping):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, np.ndarray):
        if value.dtype.kind == "f" and not np.isfinite(value).all():  # NaN: no JSON number
            return [plain(v) for v in value]
        return value.tolist()
    if isinstance(value, np.floating) and not np.isfinite(value):
        return None
    if isinstance(value, np.generic):
        return value.item()
    return value


def _entry(entry: str) -> tuple[str, str]:
    key, _, attr = entry.partition(":")
    return key.strip(), attr.strip() or key.strip()


@dataclass
class Result:
    """What an experiment's run returns: a dataclass whose JSON form (:meth:`to_dict`) is its
    :attr:`KEYS` in order, that reads back from it (:meth:`from_dict`), and that has a table
    (the console text) and figures (none by default)."""

    written: dict[str, object] | None = field(default=None, repr=False, kw_only=True)
    """The summaries of a result read back (:meth:`from_dict`, its :attr:`COMPUTED` keys);
    None for a run's result."""

    KEYS: ClassVar[tuple[str, ...]] = ()
    """The keys of the JSON form, in order: ``"key"`` (a field or method of that name) or
    ``"key: attribute"`` (an attribute, a method or a dotted path, ``"options.seeds"``); a
    ``"*attribute"`` merges the dict the attribute gives. Empty: the dataclass fields."""
    COMPUTED: ClassVar[tuple[str, ...]] = ()
    """The keys computed from what the file does not hold: a result read back holds them as
    ``written`` (a field), every one of them required."""
    LATER: ClassVar[tuple[str, ...]] = ()
    """Computed keys that files written before them lack (read back where present)."""
    SEEDS_IN_CONFIG: ClassVar[bool] = False
    """Whether the JSON form's ``"config"`` holds the seeds too (:meth:`config_and_seeds`)."""

    def _keys(self) -> tuple[str, ...]:
        if self.KEYS:
            return self.KEYS
        return tuple(f.name for f in dataclasses.fields(self) if f.repr)

    def _value(self, attr: str) -> object:
        value = functools.reduce(getattr, attr.split("."), self)  # "options.seeds": a path
        return value() if callable(value) else value

    def to_dict(self) -> JSON:
        """Everything the result states, JSON-able (``result.json``, ``--json``): the
        :attr:`KEYS` in order; a result read back gives its ``written`` summaries in place of
        the computed keys."""
        written = self.written
        out: dict[str, object] = {}
        for entry in self._keys():
            spread = entry.startswith("*")
            key, attr = _entry(entry.lstrip("*"))
            if written is not None and (spread or key in (*self.COMPUTED, *self.LATER)):
                out.update({k: v for k, v in written.items() if k not in out})
                continue
            value = plain(self._value(attr))
            if spread:
                out.update(value)
            else:
                out[key] = value
        return out

    def config_and_seeds(self) -> JSON:
        """The config's JSON form with the seeds (``"config"`` where :attr:`SEEDS_IN_CONFIG`)."""
        config: object = getattr(self, "config")  # noqa: B009 (a field of every result)
        return {**plain(config), "seeds": list(getattr(self, "seeds"))}  # noqa: B009

    @classmethod
    def read_fields(cls, obj: Mapping[str, object]) -> JSON:
        """The fields of a JSON form: each field named by a key of :attr:`KEYS` (not
        computed), typed as the field is (a config by its ``from_dict`` or its fields, a
        tuple, a float); the seeds from the config where :attr:`SEEDS_IN_CONFIG`."""
        hints = typing.get_type_hints(cls)
        names = {f.name for f in dataclasses.fields(cls) if f.init}
        values: dict[str, object] = {}
        for entry in cls.KEYS:
            key, attr = _entry(entry.lstrip("*"))
            if entry.startswith("*") or key in (*cls.COMPUTED, *cls.LATER) or key not in obj:
                continue
            if attr in names:
                values[attr] = _typed(hints[attr], obj[key])
            elif key == "config" and cls.SEEDS_IN_CONFIG:
                config = dict(as_object(obj["config"], "config"))
                values["seeds"] = check_seeds(config.pop("seeds"), "config.seeds")
                values["config"] = _typed(hints["config"], config)
        if "seeds" in values:
            values["seeds"] = check_seeds(values["seeds"], "seeds")
        return values

    @classmethod
    def from_dict(cls: type[R], data: object) -> R:
        """The result a :meth:`to_dict` wrote (``result.json``): its fields as the file holds
        them and its computed keys as ``written`` (the file holds no records)."""
        obj = as_object(data)
        values = cls.read_fields(obj)
        if cls.COMPUTED:
            values["written"] = summaries(obj, cls.COMPUTED, cls.LATER)
        return cls(**values)

    FIGURE: ClassVar[str] = ""
    """The file name of the one figure :meth:`figure` writes (:meth:`draw`; "": none)."""
    SAVE: ClassVar[Mapping[str, object]] = {"dpi": 120, "facecolor": "white"}
    """How :meth:`figure` saves it (``savefig``'s keywords)."""

    def table(self) -> str:
        """The result as console text (a few lines a person reads)."""
        raise NotImplementedError

    DRAWN_BY: ClassVar[str] = ""
    """``"module:function"`` that draws :data:`FIGURE` from the JSON form (imported when
    drawing: matplotlib only then); "": the result draws it itself (:meth:`draw`)."""

    def draw(self) -> Figure:
        """The figure of :data:`FIGURE` (a matplotlib Figure): :data:`DRAWN_BY` of the JSON
        form."""
        if not self.DRAWN_BY:
            raise NotImplementedError
        module, _, name = self.DRAWN_BY.partition(":")
        figure: Figure = getattr(importlib.import_module(module), name)(self.to_dict())
        return figure

    def caption(self) -> str:
        """The caption of :data:`FIGURE`, computed from the result."""
        return ""

    def figure(self, out_dir: Path) -> list[Path]:
        """Write the result's figures into the folder ``out_dir`` (:data:`FIGURE` and its
        caption beside it, ``.txt``); the files written (none without :data:`FIGURE`)."""
        if not self.FIGURE:
            return []
        out = Path(out_dir) / self.FIGURE
        return [save_captioned(self.draw(), out, self.caption(), **self.SAVE)]

    @classmethod
    def figure_names(cls) -> tuple[str, ...]:
        """The names of the files :meth:`figure` writes: :data:`FIGURE` and its caption (an
        experiment's ``writes``)."""
        return (cls.FIGURE, Path(cls.FIGURE).with_suffix(".txt").name) if cls.FIGURE else ()


def _typed(hint: object, value: Any) -> Any:
    """``value`` read from JSON as a field of type ``hint``."""
    kind = typing.get_origin(hint) or hint
    if isinstance(kind, type) and hasattr(kind, "from_dict"):
        return kind.from_dict(value)
    if isinstance(kind, type) and dataclasses.is_dataclass(kind):  # a computed property: not read
        given = {k: v for k, v in value.items() if not isinstance(getattr(kind, k, None), property)}
        return kind(**tuples(given))
    if kind is tuple:
        return tuple(value)
    if kind is float:
        return float(value)
    if kind is list:
        (item,) = typing.get_args(hint) or (Any,)
        return [_typed(item, v) for v in value]
    return value


_SPEC = re.compile(r"(?P<align>[<>^]?)(?P<width>\d*)")


@dataclass(frozen=True)
class Column:
    """One column of a console table: its header, the value of a row (a key of the row or a
    function of it) and the format spec (e.g. ``"9.3f"``, ``"<20s"``); the header takes the
    spec's width and alignment (numbers right, text left)."""

    name: str
    key: str | Callable[[Any], Any]
    format: str = ""
    missing: str = "-"
    """What a value of None shows."""

    def value(self, row: Any) -> Any:
        return self.key(row) if callable(self.key) else row[self.key]

    def _aligned(self, text: str) -> str:
        m = _SPEC.match(self.format)
        assert m is not None  # the pattern matches any string
        align = m["align"] or ("<" if self.format.endswith("s") else ">")
        return f"{text:{align}{m['width']}}"

    def header(self) -> str:
        return self._aligned(self.name)

    def cell(self, row: Any) -> str:
        v = self.value(row)
        return self._aligned(self.missing) if v is None else format(v, self.format)


HEADERS = {
    "name": "method",
    "view_consistency": "same unit",
    "z_error": "z error",
    "order_r2": "order R^2",
    "train_seconds": "seconds",
    "median_reference_frame_index": "RF index",
}
"""The headers of the keys several tables show; a key not here heads its own column, a key
ending in ``_worst`` (the worst seed's value) is headed ``worst``."""


def columns(*specs: str | Column, **headers: str) -> tuple[Column, ...]:
    """The columns of a table: each word ``"key:format"`` of a string a column of that key
    (headed by ``headers``, else :data:`HEADERS`), each :class:`Column` as it is."""
    out: list[Column] = []
    for spec in specs:
        if isinstance(spec, Column):
            out.append(spec)
            continue
        for word in spec.split():
            key, _, fmt = word.partition(":")
            worst = "worst" if key.endswith("_worst") else key
            out.append(Column(headers.get(key) or HEADERS.get(key, worst), key, fmt))
    return tuple(out)


def render(columns: Sequence[Column], rows: Sequence[object], sep: str = " ") -> list[str]:
    """The header line and one line per row of ``rows`` (mappings, or what the columns'
    functions read)."""
    lines = [sep.join(c.header() for c in columns)]
    lines.extend(sep.join(c.cell(r) for c in columns) for r in rows)
    return lines
