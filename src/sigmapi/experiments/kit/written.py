"""Results read back from their JSON form (``from_dict``), for the experiments whose JSON form
summarises records it does not hold (each episode, each seed's curve): such a result reads
back as its config (typed), its seeds and its summaries as the file holds them, and its
``to_dict`` gives those summaries back unchanged (``to_dict -> from_dict -> to_dict`` is the
identity). The docs read every result file through its ``from_dict``, so that a result's keys
are defined once, by the result."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any, TypeVar

from sigmapi.experiments.kit.seeds import check_seeds

__all__ = ["as_object", "config_and_seeds", "summaries", "tuples"]

C = TypeVar("C")


def as_object(data: Any, what: str = "a result's JSON form") -> Mapping[str, Any]:
    """``data`` if it is a JSON object (a TypeError naming ``what`` if not)."""
    if not isinstance(data, Mapping):
        raise TypeError(f"{what} must be a JSON object, got {type(data).__name__}")
    return data


def summaries(data: Any, required: Sequence[str], optional: Sequence[str] = ()) -> dict[str, Any]:
    """The summary keys of a result's JSON form as written: every one of ``required`` (a
    KeyError naming the first one missing) and those of ``optional`` it holds (keys a newer
    version added)."""
    obj = as_object(data)
    out = {k: obj[k] for k in required}
    out.update({k: obj[k] for k in optional if k in obj})
    return out


def tuples(table: Mapping[str, Any]) -> dict[str, Any]:
    """A config's fields as its JSON form holds them, lists as tuples (as the config has them)."""
    return {k: tuple(v) if isinstance(v, list) else v for k, v in table.items()}


def config_and_seeds(
    data: Mapping[str, Any], read: Callable[[dict[str, Any]], C]
) -> tuple[C, tuple[int, ...]]:
    """The config of a result's JSON form whose ``"config"`` holds its seeds too (``read``
    builds the config from the rest) and those seeds."""
    config = dict(as_object(data["config"], "config"))
    seeds = check_seeds(config.pop("seeds"), "config.seeds")
    return read(config), seeds
