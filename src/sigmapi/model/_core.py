"""The estimator's core: :class:`MapCore`, a map with its config, random streams and run state
(:mod:`sigmapi.model._run`), and what is read from it: the weights, the schedule now, the
responses, winners and map positions of input pairs.

:class:`~sigmapi.SigmaPiSOM` is this core with its parts: scikit-learn's parameters
(:mod:`sigmapi.model._params`), arrays, files and pickles (:mod:`sigmapi.model._persist`),
the cost (:mod:`sigmapi.model._cost`) and the training modes (:mod:`sigmapi.model.som`).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi.config import SOMConfig
from sigmapi.errors import ConfigError
from sigmapi.kernels import get_backend
from sigmapi.model import _run
from sigmapi.model._grids import GridsMixin
from sigmapi.model._run import RunState
from sigmapi.model.views import check_pairs
from sigmapi.rules import WinnerRule, winner_rule

__all__ = ["FIELDS", "MapCore", "entropy_of", "stored_overrides"]

FIELDS = tuple(f.name for f in dataclasses.fields(SOMConfig) if f.name != "extra")
"""The hyperparameters ``get_params`` lists (``extra`` holds notes, no parameter)."""


def entropy_of(seed: int | None) -> int:
    """The entropy of the random streams of ``seed``: ``seed`` itself, or fresh for None."""
    return int(np.random.SeedSequence(seed).entropy)  # type: ignore[arg-type]


def stored_overrides(cfg: SOMConfig, overrides: dict[str, object]) -> SOMConfig:
    """``cfg`` with ``overrides`` applied, keeping the caller's objects where validation only
    rebuilt an identical value (scikit-learn's ``clone`` checks that ``__init__`` kept every
    parameter as given)."""
    cfg = cfg.replace(**overrides)
    for k, v in overrides.items():
        if k in FIELDS and _identical(v, getattr(cfg, k)):
            object.__setattr__(cfg, k, v)
    return cfg


def _identical(given: Any, stored: Any) -> bool:
    """Whether ``given`` equals ``stored`` with the same types all the way down."""
    if type(given) is not type(stored):
        return False
    if isinstance(given, tuple):
        return len(given) == len(stored) and all(map(_identical, given, stored))
    return bool(given == stored)


class MapCore(GridsMixin):
    """A map of Sigma-Pi units: its config, the entropy of its random streams and its run
    state; the weights and what they answer. See :class:`~sigmapi.SigmaPiSOM`."""

    def __init__(self, config: SOMConfig | None = None, **overrides: Any) -> None:
        if config is not None and not isinstance(config, SOMConfig):
            raise ConfigError(
                f"config must be a sigmapi.SOMConfig or None, got {type(config).__name__}; "
                "pass hyperparameters as keywords instead"
            )
        cfg = config or SOMConfig()
        cfg = stored_overrides(cfg, overrides) if overrides else cfg
        self._run = RunState(cfg, entropy_of(cfg.seed), get_backend(cfg.backend))

    @property
    def config(self) -> SOMConfig:
        """The hyperparameters (change them with ``set_params``)."""
        return self._run.config

    @config.setter
    def config(self, value: SOMConfig) -> None:
        self._run.reconfigure(value)  # what set_params does once it has checked ``value``

    @property
    def seed_entropy(self) -> int:
        """The entropy of the random streams: the seed, or fresh entropy for ``seed=None``."""
        return self._run.entropy

    @seed_entropy.setter
    def seed_entropy(self, value: int) -> None:
        self._run.reseed(value)

    @property
    def t_(self) -> int:
        """Learning iterations done so far; raises :class:`NotFittedError` before fitting."""
        self._run.fitted()
        return self._run.t

    @t_.setter
    def t_(self, value: int) -> None:
        self._run.t = int(value)

    @property
    def backend(self) -> str:
        """Name of the kernel in use (one of :data:`sigmapi.kernels.BACKENDS`)."""
        return str(self._run.kernel.NAME)

    @property
    def is_fitted(self) -> bool:
        return self._run.state is not None

    @property
    def weights_(self) -> NDArray[np.float64]:
        return self._run.exported()

    def initial_weights(
        self, views: tuple[NDArray[np.float64], ...] | None = None
    ) -> NDArray[np.float64]:
        """The run's initial weights ``(n_units, n_x, n_y)``, from the ordering procedure
        (:mod:`sigmapi.rules.ordering`).

        ``ordering="none"``: uniform in ``[-init_scale, init_scale]`` (the paper), from the
        run's child stream ``spawn_key=(0,)``. ``ordering="crossview"``: an ordered start
        computed from view pairs alone: the first pairs of ``views`` when given (your own
        data), else as many pairs of the built-in task from the run's own random stream
        (child ``spawn_key=(2,)``).
        """
        return _run.initial_weights(self._run, views)

    def memory_estimate(self) -> int:
        """Bytes this model needs at its peak: the float64 start and the ordered start's
        working memory, the backend's state (its own estimate, ``kernel.memory_bytes``) and
        the float64 ``weights_``."""
        return _run.memory_estimate(self.config, self._run.kernel)

    def check_memory(self) -> None:
        """Raise :class:`~sigmapi.errors.ResourceError` (a MemoryError) before allocating if
        the machine's available memory cannot hold :meth:`memory_estimate`."""
        _run.check_memory(self.config, self._run.kernel)

    def sigma_at(self, t: int | NDArray[np.int64]) -> NDArray[np.float64]:
        """Neighbourhood width at iteration(s) t of this run's schedule, as the ordering
        procedure caps it (``crossview``: at ``ordering_sigma``)."""
        return _run.sigma_at(self.config, t)

    def eps_at(self, t: int | NDArray[np.int64]) -> NDArray[np.float64]:
        """Learning rate at iteration(s) t."""
        return _run.eps_at(self.config, t)

    @property
    def sigma_(self) -> float:
        """Neighbourhood width at the current iteration (used by the soft winner)."""
        return self._run.sigma_now()

    @property
    def winner_rule_(self) -> WinnerRule:
        """The rule training uses (a :class:`~sigmapi.rules.WinnerRule`): the one named by
        ``config.winner_rule``, as the ordering procedure trains it (``crossview``: the soft
        rule border-normalised)."""
        return _run.training_rule(self.config)

    # ------------------------------------------------------------------ using the map
    def respond(self, x: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """Activations ``h[b, k] = x_b^T W_k y_b`` of every unit; ``(B, n_units)``.

        ``x`` ``(B, n_x)`` and ``y`` ``(B, n_y)`` are codes (``x_code.encode``), flattened in
        C order. Computed by the model's kernel on its own state
        (:meth:`sigmapi.kernels.base.Kernel.activation`).
        """
        xa, ya = self._pairs_of(x, y)
        run = self._run
        return np.asarray(run.kernel.activation(run.state, xa, ya), dtype=np.float64)

    def _pairs_of(self, x: ArrayLike, y: ArrayLike) -> tuple[NDArray[np.float64], ...]:
        """Checked codes ``(B, n_x)`` and ``(B, n_y)`` of a fitted model's input pairs."""
        self._run.fitted()
        return check_pairs(x, y, self.x_shape, self.y_shape)

    def winner(
        self,
        x: ArrayLike,
        y: ArrayLike,
        rule: WinnerRule | str | None = None,
        *,
        hard: bool = False,
    ) -> NDArray[np.int64]:
        """Flat index of the winning unit per pair; ``(B,)``.

        Uses the model's winner rule (default: :attr:`winner_rule_`) or ``rule`` (a rule or
        its name), at the current sigma. ``hard=True`` takes the rule's limit at sigma -> 0
        (:attr:`~sigmapi.rules.WinnerRule.hard`): the soft winner becomes the argmax of the
        response (the metrics use this, so that mid-run maps are not smoothed).
        """
        xa, ya = self._pairs_of(x, y)
        chosen = self.winner_rule_ if rule is None else winner_rule(rule, "rule")
        if hard:
            chosen = chosen.hard
        c, run = self.config, self._run
        k = run.kernel.winners_of(run.state, xa, ya, c.geometry, chosen, self.sigma_)
        return np.asarray(k, dtype=np.int64)

    def transform(self, x: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """Map coordinates of the winner as fractions of each map axis, ``(B, d_map)`` in [0, 1]
        (on a periodic map, fractions of the turn in [0, 1): unit ``k`` of ``n`` at ``k / n``)."""
        k = self.winner(x, y)
        return self._run.unit_positions()[k]

    def unit_sqnorms(self) -> NDArray[np.float64]:
        """``|w_k|^2``, the squared length of every unit's weights; ``(n_units,)``.

        From the kernel's state (a kernel may track them), without forming ``weights_``.
        """
        state = self._run.fitted()
        return np.asarray(self._run.kernel.sqnorms(state), dtype=np.float64)

    def __repr__(self) -> str:
        fitted = f"t_={self.t_}" if self.is_fitted else "not fitted"
        return (
            f"SigmaPiSOM(map_shape={self.map_shape}, x_shape={self.x_shape}, "
            f"y_shape={self.y_shape}, backend={self.backend!r}, {fitted})"
        )
