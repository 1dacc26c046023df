"""The one typed source of defaults: :class:`SOMConfig`, its presets and overrides.

Presets are TOML files shipped in ``sigmapi/presets/``; a TOML file or ``key=value`` overrides
fill the same dataclass. Schedule milestones are fractions of the run, so ``iterations=50000``
scales the paper's schedule rather than cutting it.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
import re
import tomllib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from sigmapi import _validate
from sigmapi.codes import _WIDTH_FIX, MAX_WIDTH, MIN_WIDTH
from sigmapi.errors import ConfigError
from sigmapi.kernels import BACKEND_CHOICES
from sigmapi.rules import ORDERINGS, WINNER_RULES
from sigmapi.rules.geometry import DEFAULT_SOFT_CUT, MapGeometry
from sigmapi.rules.ordering import check_periodic_map
from sigmapi.schedules import PAPER_SIGMA, PiecewiseLinear
from sigmapi.tasks import RELATIONS

REFINE_DRAWS = ("random", "quasi")
"""How a refinement round draws its pairs on the built-in task (``SOMConfig.refine_draw``)."""

_geometry = functools.lru_cache(maxsize=64)(MapGeometry)

__all__ = [
    "MAX_EXTRA",
    "SOMConfig",
    "apply_overrides",
    "check_extra",
    "check_map_fits_task",
    "list_presets",
    "load_config_file",
    "load_preset",
    "parse_toml",
]

BACKEND_NAMES = BACKEND_CHOICES
"""The values of ``backend``: ``"auto"`` and the names of the backends (read when used)."""
MAX_INIT_SCALE = 1e15
MAX_CODE_HEIGHT = 1e7
"""Weights stay within init_scale and code_height**2 (a Kohonen update moves them towards the
data), so these bounds keep them far inside float32's range (3.4e38) even after the fast
kernel's lazy scaling (raw = W / scale, scale >= 2**-50, about 1e-15)."""
_RANGE_FIX = "weights must stay far inside float32's range; the paper uses 0.1 and 1.0"
MAX_EXTRA = 64 * 1024
"""Largest ``[extra]`` table, in bytes of JSON (a model file's header holds it)."""


def check_extra(extra: object) -> dict[str, object]:
    """``extra`` if it is a table of plain values (strings, finite numbers, bools, lists and
    tables of them) of at most :data:`MAX_EXTRA` bytes of JSON; else a ConfigError naming it."""
    if not isinstance(extra, dict):
        raise ConfigError(f"extra must be a table, got {extra!r}")

    def plain(v: object, where: str) -> None:
        if isinstance(v, dict):
            for k, item in v.items():
                if not isinstance(k, str):
                    raise ConfigError(f"{where} has a key {k!r} that is not a string")
                plain(item, f"{where}.{k}")
        elif isinstance(v, (list, tuple)):
            for i, item in enumerate(v):
                plain(item, f"{where}[{i}]")
        elif isinstance(v, float) and not math.isfinite(v):
            raise ConfigError(f"{where} must be a finite number, got {v!r}")
        elif not isinstance(v, (str, int, float, bool)):
            raise ConfigError(
                f"{where} must be a string, number, bool, or a list or table of them, got "
                f"{type(v).__name__} {v!r}; write dates and times as strings"
            )

    plain(extra, "extra")
    size = len(json.dumps(extra))
    if size > MAX_EXTRA:
        raise ConfigError(
            f"extra must be at most {MAX_EXTRA} bytes of JSON, got {size}; keep notes short "
            "and put data in files of their own"
        )
    return extra


@dataclass(frozen=True)
class SOMConfig:
    """Hyperparameters of a Sigma-Pi SOM run. Defaults: the authors' 1-D sizes and schedule
    with sigmapi's ordered start (``ordering="crossview"``) and no refinement; the preset
    ``paper-1d-authors`` is the authors' script (``ordering="none"``), ``paper-1d`` adds three
    refinement rounds."""

    map_shape: tuple[int, ...] = (15,)
    """Grid of map units, e.g. (15,) or (15, 15); the paper's Fig. 8 uses 15x15."""
    x_shape: tuple[int, ...] = (15,)
    """Grid of the x input (retinal position) code."""
    y_shape: tuple[int, ...] = (15,)
    """Grid of the y input (gaze direction) code; same number of dimensions as x."""
    code_width: float = field(
        default=0.5, metadata=_validate.bounded("width", MIN_WIDTH, fix=_WIDTH_FIX)
    )
    """Standard deviation of the input hills in grid units (1-D script: 0.5)."""
    code_height: float = field(
        default=1.0,
        metadata=_validate.bounded("number", 0, MAX_CODE_HEIGHT, lo_open=True, fix=_RANGE_FIX),
    )
    """Peak of the input hills before normalisation."""
    code_normalize: bool = field(default=True, metadata=_validate.bounded("bool"))
    """L2-normalise input codes to length 1 (the script does)."""
    periodic: bool = field(default=False, metadata=_validate.bounded("bool"))
    """Periodic input axes (rings); the paper's are bounded."""
    map_periodic: bool = field(default=False, metadata=_validate.bounded("bool"))
    """Periodic map: every map axis wraps around (a ring in 1-D, a torus in 2-D), in the
    neighbourhood and the soft winner's smoothing; the paper's map is bounded. For angles,
    with ``periodic`` codes and the relation "sum_mod"."""
    relation: str = field(default="mean", metadata=_validate.bounded("choice", options=RELATIONS))
    """z = f(x, y): "mean" (the paper, z = (x + y) / 2), "sum", "difference", or "sum_mod"
    (angles: z = (x + y) mod 1, needs ``periodic`` codes)."""
    iterations: int = field(
        default=300_000, metadata=_validate.bounded("int", 1, fix="the paper runs 300000")
    )
    """Length of the run; schedule milestones are fractions of it."""
    eps: float | tuple[tuple[float, float], ...] = 0.01
    """Learning rate: a constant, or [fraction, value] knots of a piecewise-linear schedule."""
    sigma: tuple[tuple[float, float], ...] = PAPER_SIGMA.knots
    """Neighbourhood width on the map (grid units): [fraction, value] knots (8 -> 3.5 -> 1e-5)."""
    winner_rule: str = field(
        default="soft", metadata=_validate.bounded("choice", options=WINNER_RULES)
    )
    """"soft" (Gaussian-smoothed argmax, the paper; border-normalised under an ordering
    procedure, see ``ordering``), "soft_mean" (always border-normalised), "argmax", or
    "min_distance"."""
    soft_cut: int = field(
        default=DEFAULT_SOFT_CUT,
        metadata=_validate.bounded("int", 0, fix="in map units; the script uses 15"),
    )
    """Half-width of the smoothing window of the soft winner, in map units (script: 15)."""
    init_scale: float = field(
        default=0.1,
        metadata=_validate.bounded("number", 0, MAX_INIT_SCALE, lo_open=True, fix=_RANGE_FIX),
    )
    """Initial weights are uniform in [-init_scale, init_scale] (paper: 0.1)."""
    ordering: str = field(
        default="crossview", metadata=_validate.bounded("choice", options=ORDERINGS)
    )
    """How the map comes to be ordered: "crossview" (sigmapi's: an ordered start computed from
    the views alone, the neighbourhood capped at ``ordering_sigma`` and the soft winner
    normalised at the map border; see :mod:`sigmapi.rules.ordering`) or "none" (the paper's
    random start and schedule, bit for bit)."""
    ordering_sigma: float = field(default=3.0, metadata=_validate.bounded("width", 0, lo_open=True))
    """With an ordering procedure: the largest neighbourhood width used (map units); the
    configured sigma schedule is cut off at this value. Ignored with ordering = "none"."""
    refine_rounds: int = field(
        default=0, metadata=_validate.bounded("int", 0, fix="0 turns the refinement off")
    )
    """Rounds of the batch refinement after training (:mod:`sigmapi.rules.refinement`, section
    6.3): hard winners of view 0 with the weights fixed, then every unit's weights to the
    mean of view 1's outer products over the pairs it won. 0 = off (the run as before)."""
    refine_pairs: int = field(default=200_000, metadata=_validate.bounded("int", 1))
    """View pairs per refinement round on the built-in task (fresh pairs from the run's own
    stream); with ``fit(views)`` a round is one pass over your rows instead."""
    refine_sigma: float = field(
        default=0.0, metadata=_validate.bounded("width", 0, fix="0 is the winner alone")
    )
    """Neighbourhood width of the refinement's weighted mean (map units); 0 = each unit the
    mean of the pairs it won alone."""
    refine_tol: float = field(
        default=0.0,
        metadata=_validate.bounded(
            "number", 0, 1, hi_open=True, fix="0 is the kernel's own arithmetic, bit for bit"
        ),
    )
    """The refinement's fast path (fast kernel, hard winners): 0 runs it on the kernel's own
    arithmetic, bit for bit; above 0 it skips the input pairs below ``max(kernel_tol,
    refine_tol)`` of their peak in its winner search and sums, takes the best of the search's
    float32 scores without the exact re-check, keeps its sums in float32 and draws its codes
    within rounding (normalised hills multiplied out): cheaper per pair, the same maps within
    a stated tolerance (docs/guide/ceiling.md)."""
    refine_draw: str = field(
        default="random", metadata=_validate.bounded("choice", options=REFINE_DRAWS)
    )
    """How a refinement round on the built-in task draws its pairs: ``"random"`` (each block
    from its own random stream, as the training does) or ``"quasi"`` (the round's pairs at
    the points of a randomly shifted Kronecker sequence, :func:`sigmapi.tasks.kronecker`:
    the same distribution, spread evenly, so that each unit's mean of view 1's outer
    products converges faster; docs/guide/ceiling.md, "Quasi-random pairs")."""
    same_view: bool = field(default=False, metadata=_validate.bounded("bool"))
    """Ablation: learn from the view that chose the winner (the paper learns from the other)."""
    backend: str = field(
        default="auto", metadata=_validate.bounded("choice", options=BACKEND_NAMES)
    )
    """Kernel: "auto" (the fast kernel where numba imports, else the reference kernel) or a
    backend's name (:data:`sigmapi.kernels.BACKENDS`)."""
    kernel_tol: float = field(
        default=1e-6,
        metadata=_validate.bounded(
            "number", 0, 1, hi_open=True, fix="0 is exact; the default is 1e-6"
        ),
    )
    """Fast kernel: code and neighbourhood values below kernel_tol x their maximum are skipped
    (0 = exact). The reference kernel is always exact."""
    threads: bool = field(default=False, metadata=_validate.bounded("bool"))
    """Fast kernel: train on numba's threads (the same result) when the map is large enough
    (``K * n_x * n_y >= 2**18``, e.g. paper-2d); pays off on an otherwise idle machine."""
    seed: int | None = field(
        default=None,
        metadata=_validate.bounded("int", 0, fix="or None for fresh entropy", none=True),
    )
    """Seed of every random stream of the run (weights and data); None draws fresh entropy."""

    extra: dict[str, object] = field(default_factory=dict, compare=False, repr=False)
    """Unused by the SOM: free-form notes carried from the preset (e.g. its source)."""

    def __post_init__(self) -> None:
        """The shapes, then every field's declared bounds (:func:`sigmapi._validate.
        check_fields`, the one validator of declared bounds), then the rules between fields
        and the schedules."""
        set_ = object.__setattr__
        for name in ("map_shape", "x_shape", "y_shape"):
            set_(self, name, _validate.shape(name, getattr(self, name)))
        if len(self.x_shape) != len(self.y_shape):
            raise ConfigError(
                f"x_shape and y_shape must have the same number of dimensions, got "
                f"{self.x_shape} and {self.y_shape}"
            )
        weights = math.prod(self.map_shape) * math.prod(self.x_shape) * math.prod(self.y_shape)
        if weights > 2**56:  # past any memory; int64 byte counts downstream stay exact
            raise ConfigError(
                f"map_shape x x_shape x y_shape must hold at most 2**56 weights, got {weights:,} "
                f"({self.map_shape} x {self.x_shape} x {self.y_shape}); use smaller shapes"
            )
        _validate.check_fields(self)
        if self.ordering == "crossview":
            check_periodic_map(self.map_shape, self.map_periodic)
        if RELATIONS[self.relation].circular and not self.periodic:
            raise ConfigError(
                f"relation {self.relation!r} relates angles (0 and 1 are the same place), so "
                "it needs periodic codes, got periodic = false; set periodic = true"
            )
        eps = PiecewiseLinear.coerce(self.eps, "eps")
        vals = [v for _, v in eps.knots]
        if min(vals) <= 0 or max(vals) > 1:
            raise ConfigError(f"eps values must lie in (0, 1], got {vals}; the paper uses 0.01")
        set_(
            self,
            "eps",
            eps.knots[0][1] if len(eps.knots) == 1 and eps.knots[0][0] == 0 else eps.knots,
        )
        sig = PiecewiseLinear.coerce(self.sigma, "sigma")
        if max(v for _, v in sig.knots) > MAX_WIDTH:
            raise ConfigError(
                f"sigma values must be <= {MAX_WIDTH:g} (map units), got "
                f"{[v for _, v in sig.knots]}; a neighbourhood wider than the map is flat already"
            )
        if min(v for _, v in sig.knots) <= 0:
            raise ConfigError(
                f"sigma values must be > 0 (map units), got {[v for _, v in sig.knots]}; "
                "use a small value such as 1e-5 for a winner-only update"
            )
        set_(self, "sigma", sig.knots)
        set_(self, "extra", check_extra(self.extra))

    @property
    def sigma_schedule(self) -> PiecewiseLinear:
        return PiecewiseLinear.coerce(self.sigma, "sigma")

    @property
    def eps_schedule(self) -> PiecewiseLinear:
        return PiecewiseLinear.coerce(self.eps, "eps")

    @property
    def geometry(self) -> MapGeometry:
        """The map as the kernels compute on it, one value: ``map_shape``, ``map_periodic``
        and ``soft_cut`` (:class:`~sigmapi.rules.geometry.MapGeometry`, made once per
        config)."""
        return _geometry(self.map_shape, self.map_periodic, self.soft_cut)

    def replace(self, **changes: Any) -> SOMConfig:
        """A copy with ``changes``; unknown names raise a ConfigError listing the valid ones."""
        _check_keys(changes)
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, object]:
        """JSON/TOML-able dict of every field (tuples become lists)."""
        out: dict[str, object] = {}
        for f in dataclasses.fields(self):
            out[f.name] = _plain(getattr(self, f.name))
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> SOMConfig:
        """Build from a dict such as a parsed TOML file; unknown keys are an error."""
        if not isinstance(data, dict):
            raise ConfigError(
                f"a config must be a table of key = value pairs, got {type(data).__name__}"
            )
        _check_keys(data)
        kwargs = dict(data)
        for key in ("map_shape", "x_shape", "y_shape"):
            if key in kwargs and isinstance(kwargs[key], list):
                kwargs[key] = tuple(kwargs[key])
        return cls(**kwargs)


def _plain(value: object) -> object:
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    return value


def _check_keys(data: Iterable[str]) -> None:
    names = {f.name for f in dataclasses.fields(SOMConfig)}
    unknown = sorted(set(data) - names)
    if unknown:
        raise ConfigError(
            f"unknown config key {unknown[0]!r}; valid keys are: {', '.join(sorted(names))}"
        )


# ---------------------------------------------------------------------------- presets and files


def list_presets() -> list[str]:
    """Names of the presets shipped with the package."""
    files = resources.files("sigmapi").joinpath("presets")
    return sorted(p.name[:-5] for p in files.iterdir() if p.name.endswith(".toml"))


def parse_toml(text: str, source: str) -> dict[str, object]:
    """The table of TOML ``text``; a ConfigError naming ``source`` (a preset, a file) where it
    is not valid TOML. The presets', the config files' and the sweep files' one parser."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{source} is not valid TOML: {exc}") from None
    return data


def load_preset(name: str) -> SOMConfig:
    """The :class:`SOMConfig` of a shipped preset, e.g. ``"paper-1d"``."""
    names = list_presets()
    if name not in names:
        raise ConfigError(f"unknown preset {name!r}; available presets: {', '.join(names)}")
    text = resources.files("sigmapi").joinpath("presets", f"{name}.toml").read_text("utf-8")
    return _from_toml(parse_toml(text, f"preset {name!r}"), f"preset {name!r}")


def load_config_file(path: str | Path, base: SOMConfig | None = None) -> SOMConfig:
    """Read a TOML config file; its keys override ``base`` (default: the dataclass defaults)."""
    p = Path(path)
    if not p.is_file():
        raise ConfigError(f"config file {str(p)!r} does not exist; check the path")
    try:
        text = p.read_text("utf-8-sig")  # a byte order mark (Windows editors) is no key
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"config file {str(p)!r} cannot be read as UTF-8 text: {exc}") from None
    data = parse_toml(text, f"config file {str(p)!r}")
    return _from_toml(data, f"config file {str(p)!r}", base)


def _from_toml(data: dict[str, object], source: str, base: SOMConfig | None = None) -> SOMConfig:
    data = dict(data)
    extra = data.pop("extra", {})
    if not isinstance(extra, dict):
        raise ConfigError(f"{source}: [extra] must be a table, got {extra!r}")
    try:
        merged = (base or SOMConfig()).to_dict()
        _check_keys(data)
        merged.update(data)
        old = merged.get("extra")
        merged["extra"] = {**(old if isinstance(old, dict) else {}), **extra}
        return SOMConfig.from_dict(merged)
    except ConfigError as exc:
        raise ConfigError(f"{source}: {exc}") from None
    except TypeError as exc:
        raise ConfigError(f"{source}: {exc}") from None


def parse_override(item: str) -> tuple[str, object]:
    """Parse ``key=value``; the value is read as TOML (numbers, true/false, lists) or a string."""
    if "=" not in item:
        raise ConfigError(f"an override must be key=value, got {item!r}; e.g. iterations=50000")
    key, _, raw = item.partition("=")
    key = key.strip()
    raw = raw.strip()
    if not key:
        raise ConfigError(
            f"an override must be key=value with a non-empty key, got {item!r}; "
            "e.g. iterations=50000"
        )
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = _shape_text(raw)
    return key, value


_GRID_TEXT = re.compile(r"\d+(?:\s*x\s*\d+)+")
_TUPLE_TEXT = re.compile(r"\(\s*\d+\s*(?:,\s*\d+\s*)*,?\s*\)")


def _shape_text(raw: str) -> str | tuple[int, ...]:
    """``raw`` as a grid when it is written as the command line writes one (``15x15``, the
    option ``--map-shape``'s form) or as a Python tuple of ints (``(15,)``, the form of the
    shape errors' examples); any other text stays a string."""
    if _GRID_TEXT.fullmatch(raw.lower()):
        return tuple(int(v) for v in raw.lower().split("x"))
    if _TUPLE_TEXT.fullmatch(raw):
        return tuple(int(v) for v in raw.strip("() ").split(",") if v.strip())
    return raw


SHAPE_KEYS = ("map_shape", "x_shape", "y_shape")
"""The keys that set the map's and the task's dimensions (:func:`check_map_fits_task`)."""


def check_map_fits_task(cfg: SOMConfig) -> SOMConfig:
    """``cfg`` if its map has as many axes as its task (``x_shape``), else a ConfigError
    naming both settings.

    A map of another dimension than the task it learns cannot lay the task out on its grid:
    a 2-D map on the 1-D task folds whatever the seed. The SOM itself accepts such shapes
    (they are plain array sizes for the user's own codes); the commands that train on a
    preset's task check them (``sigmapi train``, the overrides of a preset).
    """
    m, t = len(cfg.map_shape), len(cfg.x_shape)

    def axes(n: int) -> str:
        return f"{n} axis" if n == 1 else f"{n} axes"

    if m != t:
        raise ConfigError(
            f"map_shape {cfg.map_shape} has {axes(m)}, but the task is {t}-D (x_shape "
            f"{cfg.x_shape}, y_shape {cfg.y_shape}): a {m}-D map cannot lay out a {t}-D task "
            f"(it folds whatever the seed); give map_shape {axes(t)}, e.g. map_shape="
            f"{'x'.join(['15'] * t)}, or x_shape and y_shape of {axes(m)} for the {m}-D task"
        )
    return cfg


def apply_overrides(cfg: SOMConfig, items: list[str]) -> SOMConfig:
    """Apply ``key=value`` overrides to ``cfg`` (each a field of :class:`SOMConfig`)."""
    changes: dict[str, object] = {}
    for item in items:
        key, value = parse_override(item)
        changes[key] = value
    if not changes:
        return cfg
    merged = cfg.to_dict()
    _check_keys(changes)
    merged.update(changes)
    try:
        out = SOMConfig.from_dict(merged)
    except TypeError as exc:
        raise ConfigError(f"override: {exc}") from None
    return check_map_fits_task(out) if set(changes) & set(SHAPE_KEYS) else out
