"""Configs made of parts (:class:`Parts`): frozen dataclasses (``env``, ``map``, ``agent``,
``run``, ...) held by one config whose command-line options are every part's fields."""

from __future__ import annotations

import dataclasses
import inspect
import typing
from collections.abc import Mapping
from dataclasses import field
from typing import ClassVar, Self

from sigmapi import _validate
from sigmapi.errors import ConfigError
from sigmapi.experiments.kit.results import tuples


class Parts:
    """The base of a config made of parts: every dataclass field is a part, a frozen dataclass
    of its own (:attr:`PARTS`, derived from the fields, never listed again). Field names are
    unique across the parts, so ``config.replace(grid=7, episodes=150)`` finds each one's part."""

    PARTS: ClassVar[dict[str, type]]
    """Each part's name and class, in the order of the fields."""

    def __init_subclass__(cls, **kwargs: object) -> None:
        super().__init_subclass__(**kwargs)
        hints = typing.get_type_hints(cls)
        own = {k: hints[k] for k in inspect.get_annotations(cls)}
        cls.PARTS = {k: v for k, v in own.items() if typing.get_origin(v) is not ClassVar}
        for name, part in cls.PARTS.items():
            if not (isinstance(part, type) and dataclasses.is_dataclass(part)):
                raise TypeError(f"part {name!r} of {cls.__name__} must be a dataclass, got {part}")

    @classmethod
    def kind(cls) -> str:
        """The experiment's word in messages: the class name without ``Config``, lower case."""
        return cls.__name__.removesuffix("Config").lower()

    def replace(self, **changes: object) -> Self:
        """A copy with ``changes``, fields of any part by name (``grid=7, episodes=150``); an
        unknown field is a ConfigError that lists the valid ones."""
        owner = {f.name: p for p, cls in self.PARTS.items() for f in dataclasses.fields(cls)}
        bad = sorted(set(changes) - set(owner))
        if bad:
            valid = ", ".join(sorted(owner))
            raise ConfigError(f"unknown {self.kind()} config field {bad[0]!r}; valid: {valid}")
        parts = {p: {k: v for k, v in changes.items() if owner[k] == p} for p in self.PARTS}
        return type(self)(
            **{p: dataclasses.replace(getattr(self, p), **c) for p, c in parts.items()}
        )

    def to_dict(self) -> dict[str, object]:
        """The parts as JSON-able tables (tuples as lists): ``{"env": {...}, "map": ...}``."""
        return dict(parts_dict(self, self.PARTS))

    @classmethod
    def from_dict(cls, data: object) -> Self:
        """The config a :meth:`to_dict` wrote (lists as tuples): each part's table must hold
        only its class's fields (a ConfigError naming the first that is not one; a KeyError
        naming a missing part)."""
        kind = cls.kind()
        if not isinstance(data, Mapping):
            raise _validate.fail(f"{kind} config", "a JSON object of parts", type(data).__name__)
        out = {}
        for part, part_cls in cls.PARTS.items():
            table = data[part]
            if not isinstance(table, Mapping):
                raise _validate.fail(f"{kind} config part {part!r}", "a JSON object", table)
            names = {f.name for f in dataclasses.fields(part_cls)}
            bad = sorted(set(table) - names)
            if bad:
                raise ConfigError(
                    f"unknown {kind} config field {bad[0]!r} in part {part!r}; valid: "
                    f"{', '.join(sorted(names))}"
                )
            out[part] = part_cls(**tuples(table))
        return cls(**out)


def parts_of(config_type: type) -> dict[str, type]:
    """The parts of a config type (:attr:`Parts.PARTS`; empty for a config of plain fields)."""
    return dict(config_type.PARTS) if issubclass(config_type, Parts) else {}


def check_part_types(config: object, parts: dict[str, type]) -> None:
    """Each part of ``config`` is of its class (a ConfigError naming the first that is not)."""
    for name, cls in parts.items():
        if not isinstance(getattr(config, name), cls):
            raise _validate.fail(name, f"a {cls.__name__}", getattr(config, name))


def parts_dict(config: object, parts: dict[str, type]) -> dict[str, dict[str, object]]:
    """The parts of ``config`` as JSON-able tables (tuples as lists)."""
    return {
        part: {
            k: (list(v) if isinstance(v, tuple) else v)
            for k, v in dataclasses.asdict(getattr(config, part)).items()
        }
        for part in parts
    }


def count_field(default: int) -> int:
    """A config field counting episodes, blocks, pairs or tests: an int from 1 to 1,000,000
    (the bound declared once, shown in ``--help``), ``default`` unless given."""
    return field(default=default, metadata=_validate.bounded("int", 1, 1_000_000))
