"""A map's settings as data, resolved once (:class:`MapSpec`): how every experiment that trains a
Sigma-Pi map names it (a schedule of its own is a preset too, e.g. ``robot-2d``)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from sigmapi.config import SOMConfig, apply_overrides, load_preset


@dataclass(frozen=True)
class MapSpec:
    """A shipped preset, then ``changes`` (typed, the experiment's), then ``overrides``
    (``key=value`` strings as ``--set`` takes them, the user's); :meth:`config` adds last the
    fields the experiment fixes (the world's codes, the map's size, length, seed and backend).

    Examples
    --------
    >>> spec = MapSpec("paper-1d", overrides=("iterations=5000",), changes={"refine_rounds": 0})
    >>> cfg = spec.config(seed=3)
    >>> (cfg.iterations, cfg.refine_rounds, cfg.seed)
    (5000, 0, 3)
    """

    preset: str
    """A shipped preset's name (``sigmapi presets``)."""
    overrides: tuple[str, ...] = ()
    """``key=value`` changes to it, as ``--set`` takes them (applied after ``changes``)."""
    changes: Mapping[str, object] = field(default_factory=dict)
    """Typed changes the experiment makes to the preset (before the user's overrides)."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "overrides", tuple(self.overrides))
        object.__setattr__(self, "changes", dict(self.changes))  # a copy (picklable)

    def config(self, **fixed: Any) -> SOMConfig:
        """The preset with ``changes``, ``overrides`` and then ``fixed`` (the fields the
        experiment sets: codes, sizes, length, seed, backend)."""
        cfg = load_preset(self.preset)
        if self.changes:
            cfg = cfg.replace(**self.changes)
        cfg = apply_overrides(cfg, list(self.overrides))
        return cfg.replace(**fixed) if fixed else cfg
