"""One seed plan: the random streams of one seed of an experiment, each by name.

Every experiment takes its seeds as ints (:func:`check_seeds`) and draws each random stream from
a :class:`SeedPlan`: stream ``name`` of seed ``s`` is ``SeedSequence(s, spawn_key=(key,
*more))``, the plan naming ``key`` (``more``: keys below it, e.g. one per episode), handed out
as generators or sequences, never ints. A model is built with the seed ``s`` itself, its own
streams the children :data:`MODEL_KEYS` (0-4) of the same tree, so a plan's keys start at 5
and two models of one seed draw the same streams. An environment is seeded from a generator
of the plan, one per episode, as its ``np_random`` (:func:`~sigmapi.agents.reset_from`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from sigmapi import _validate
from sigmapi.errors import ConfigError

MODEL_KEYS = range(5)
"""Spawn keys under which a model of seed ``s`` draws its own streams (weights, data, ...)."""


@dataclass(frozen=True)
class SeedPlan:
    """The named streams of an experiment's seeds (see the module's docstring).

    Examples
    --------
    >>> plan = SeedPlan({"map": 5, "starts": 6})
    >>> plan.sequence(3, "starts").spawn_key
    (6,)
    >>> plan.sequence(3, "starts", 20).spawn_key
    (6, 20)
    >>> [int(g.integers(10)) for g in plan.rngs(3, "starts", 2)] == [
    ...     int(plan.rng(3, "starts", i).integers(10)) for i in range(2)]
    True
    """

    keys: Mapping[str, int]
    """The spawn key of each stream, by name (none of :data:`MODEL_KEYS`)."""

    def __post_init__(self) -> None:
        if len(set(self.keys.values())) != len(self.keys):
            raise ValueError(f"two streams of a seed plan share a spawn key: {dict(self.keys)}")
        model = sorted(k for k, v in self.keys.items() if v in MODEL_KEYS)
        if model:
            raise ValueError(
                f"streams {model} of a seed plan take spawn keys of a model of the seed "
                f"({MODEL_KEYS.start}-{MODEL_KEYS.stop - 1}): give them keys from "
                f"{MODEL_KEYS.stop} up"
            )
        object.__setattr__(self, "keys", dict(self.keys))  # a copy (picklable)

    def sequence(self, seed: int, name: str, *more: int) -> np.random.SeedSequence:
        """The ``SeedSequence`` of stream ``name`` of ``seed`` (``more``: further keys below
        it, e.g. one stream per dwell time)."""
        return np.random.SeedSequence(seed, spawn_key=(self.keys[name], *more))

    def rng(self, seed: int, name: str, *more: int) -> np.random.Generator:
        """A generator of stream ``name`` of ``seed`` (:meth:`sequence`)."""
        return np.random.default_rng(self.sequence(seed, name, *more))

    def rngs(self, seed: int, name: str, n: int) -> list[np.random.Generator]:
        """``n`` generators of stream ``name`` of ``seed``, one per item (``rng(seed, name,
        i)`` for ``i < n``): an episode's start is a function of the seed and the episode
        alone, however many draws the episodes before it took."""
        return [self.rng(seed, name, i) for i in range(n)]


def check_seeds(seeds: Any, name: str = "seeds") -> tuple[int, ...]:
    """``seeds`` as a tuple of ints: at least one, each >= 0, no two alike (``name``: where they
    came from, e.g. ``"sweep spec 'a.toml': seeds"``).

    Examples
    --------
    >>> check_seeds([2, 0, 1])
    (2, 0, 1)
    >>> check_seeds([0, 0])
    Traceback (most recent call last):
    ...
    sigmapi.errors.ConfigError: seeds must be distinct, got [0, 0]; e.g. [0, 1, 2]
    """
    fix = "e.g. [0, 1, 2]"
    if isinstance(seeds, (str, bytes)) or not isinstance(seeds, Sequence):
        raise _validate.fail(name, "a list of non-negative ints", seeds, fix)
    if not seeds:
        raise ConfigError(f"{name} must name at least one seed, got none; {fix}")
    if not all(_validate.is_int(s) and s >= 0 for s in seeds):
        raise _validate.fail(name, "a list of non-negative ints", list(seeds), fix)
    if len(set(seeds)) != len(seeds):
        raise _validate.fail(name, "distinct", list(seeds), fix)
    return tuple(int(s) for s in seeds)
