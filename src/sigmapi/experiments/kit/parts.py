"""Configs made of parts: frozen dataclasses (``env``, ``map``, ``agent``, ``run``, ...) held
by one config whose ``PARTS`` class attribute names each part's class. Field names are unique
across the parts, so ``config.replace(grid=7, episodes=150)`` finds each field's part, and the
command line gives every part's fields as options (:mod:`sigmapi.cli.experiment`)."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from sigmapi import _validate
from sigmapi.errors import ConfigError
from sigmapi.experiments.kit.written import tuples

__all__ = ["check_part_types", "parts_dict", "parts_from_dict", "replaced_parts"]


def check_part_types(config: Any, parts: dict[str, type]) -> None:
    """Each part of ``config`` is of its class (a ConfigError naming the first that is not)."""
    for name, cls in parts.items():
        if not isinstance(getattr(config, name), cls):
            raise _validate.fail(name, f"a {cls.__name__}", getattr(config, name))


def replaced_parts(
    config: Any, parts: dict[str, type], changes: dict[str, Any], kind: str
) -> dict[str, Any]:
    """The parts of ``config`` with ``changes`` (fields of any part, by name); an unknown
    field is a ConfigError that lists the valid ones (``kind``: "reach", "reward", ...)."""
    owner = {f.name: part for part, cls in parts.items() for f in dataclasses.fields(cls)}
    bad = sorted(set(changes) - set(owner))
    if bad:
        raise ConfigError(
            f"unknown {kind} config field {bad[0]!r}; valid: {', '.join(sorted(owner))}"
        )
    return {
        part: dataclasses.replace(
            getattr(config, part), **{k: v for k, v in changes.items() if owner[k] == part}
        )
        for part in parts
    }


def parts_dict(config: Any, parts: dict[str, type]) -> dict[str, dict[str, Any]]:
    """The parts of ``config`` as JSON-able tables (tuples as lists)."""
    return {
        part: {
            k: (list(v) if isinstance(v, tuple) else v)
            for k, v in dataclasses.asdict(getattr(config, part)).items()
        }
        for part in parts
    }


def parts_from_dict(data: Any, parts: dict[str, type], kind: str) -> dict[str, Any]:
    """The parts a :func:`parts_dict` wrote, built again (lists as tuples): each part's
    table must hold only its class's fields (a ConfigError naming the first that is not one;
    a KeyError naming a missing part)."""
    if not isinstance(data, Mapping):
        raise _validate.fail(f"{kind} config", "a JSON object of parts", type(data).__name__)
    out = {}
    for part, cls in parts.items():
        table = data[part]
        if not isinstance(table, Mapping):
            raise _validate.fail(f"{kind} config part {part!r}", "a JSON object", table)
        names = {f.name for f in dataclasses.fields(cls)}
        bad = sorted(set(table) - names)
        if bad:
            raise ConfigError(
                f"unknown {kind} config field {bad[0]!r} in part {part!r}; valid: "
                f"{', '.join(sorted(names))}"
            )
        out[part] = cls(**tuples(table))
    return out
