"""One seed plan: the random streams of one seed of an experiment, each by name.

Every experiment takes its seeds as ints (:func:`check_seeds`) and
draws each of its random streams from a :class:`SeedPlan`: ``plan.rng(seed, "starts")`` is
``default_rng(plan.sequence(seed, "starts"))``, a child ``SeedSequence`` of the seed with the
spawn key the plan names. A stream is never turned into an int and back.

Two derivations, so that published results stay as they were:

- the seed as entropy (``root=None``): ``SeedSequence(seed, spawn_key=(key, *more))``. A
  :class:`~sigmapi.SigmaPiSOM` built with the same seed draws its own streams under spawn
  keys 0-4 (:data:`MODEL_KEYS`), so a plan whose experiment builds such a model with that
  seed names keys outside them (chain 16, compare 13, stream 7);
- under a fixed root (``root=0``, reach and reward): ``SeedSequence(root, spawn_key=(seed,
  key, *more))``: seed ``s`` is child ``s`` of ``SeedSequence(root)``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from sigmapi import _validate
from sigmapi.errors import ConfigError

__all__ = ["MODEL_KEYS", "SeedPlan", "check_seeds"]

MODEL_KEYS = range(5)
"""Spawn keys under which a model of seed ``s`` draws its own streams (weights, data, ...)."""


@dataclass(frozen=True)
class SeedPlan:
    """The named streams of an experiment's seeds (see the module's docstring).

    Examples
    --------
    >>> plan = SeedPlan({"map": 0, "starts": 1}, root=0)
    >>> plan.sequence(3, "starts").spawn_key
    (3, 1)
    >>> SeedPlan({"frames": 7}).sequence(3, "frames", 20).spawn_key
    (7, 20)
    """

    keys: Mapping[str, int]
    """The spawn key of each stream, by name."""
    root: int | None = None
    """None: the seed is the entropy; an int: the seed is a child of ``SeedSequence(root)``."""

    def __post_init__(self) -> None:
        if len(set(self.keys.values())) != len(self.keys):
            raise ValueError(f"two streams of a seed plan share a spawn key: {dict(self.keys)}")
        object.__setattr__(self, "keys", dict(self.keys))  # a copy (picklable)

    def sequence(self, seed: int, name: str, *more: int) -> np.random.SeedSequence:
        """The ``SeedSequence`` of stream ``name`` of ``seed`` (``more``: further keys below
        it, e.g. one stream per dwell time)."""
        key = self.keys[name]
        if self.root is None:
            return np.random.SeedSequence(seed, spawn_key=(key, *more))
        return np.random.SeedSequence(self.root, spawn_key=(seed, key, *more))

    def rng(self, seed: int, name: str, *more: int) -> np.random.Generator:
        """A generator of stream ``name`` of ``seed`` (:meth:`sequence`)."""
        return np.random.default_rng(self.sequence(seed, name, *more))


def check_seeds(seeds: Any, name: str = "seeds") -> tuple[int, ...]:
    """``seeds`` as a tuple of ints: at least one, each >= 0, no two alike.

    The one check of every experiment's seeds (``name`` says where they came from, e.g.
    ``"sweep spec 'a.toml': seeds"``).

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
