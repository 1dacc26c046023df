"""The rules of the Sigma-Pi SOM, each defined once, with its reference arithmetic (NumPy).

- :mod:`~sigmapi.rules.geometry`: the map's geometry as one value (grid, periodic axes, the
  soft winner's window), what the winner rules and the kernels compute on;
- :mod:`~sigmapi.rules.winners`: winner rules (``soft``, ``argmax``, ``min_distance``,
  ``soft_mean``): scores, norms needed, hard limit, border-normalised variant;
- :mod:`~sigmapi.rules.neighbourhood`: the Gaussian over the map, bounded or periodic (the
  neighbourhood and the soft winner's smoothing);
- :mod:`~sigmapi.rules.learning`: the Kohonen learning rule;
- :mod:`~sigmapi.rules.ordering`: ordering procedures (``none``, ``crossview``): initial
  weights, sigma cap, the rule training uses;
- :mod:`~sigmapi.rules.refinement`: the batch refinement after training (section 6.3: hard
  winners with the weights fixed, weights to the mean of their pairs).

Each kind has a registry, a dict name -> object: :data:`WINNER_RULES`,
:data:`NEIGHBOURHOODS`, :data:`LEARNING_RULES`, :data:`ORDERINGS`,
:data:`REFINEMENTS`. The config's string fields look up there (:func:`lookup`). The kernels
(:mod:`sigmapi.kernels`) compute the rules: the reference kernel by calling the objects'
arithmetic, a compiled kernel by its compiled form of the rules it declares
(``kernel.supports(rule)``).

Adding a winner rule: a :class:`~sigmapi.rules.winners.WinnerRule` subclass and its entry in
:data:`WINNER_RULES` (``rules/winners.py``); for the fast kernel, its compiled form
(``kernels/_rows.py``, ``_winner``) and code (``kernels/fast.py``, ``COMPILED``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TypeVar

from sigmapi import _validate
from sigmapi.rules.geometry import MapGeometry
from sigmapi.rules.learning import KOHONEN, LEARNING_RULES, Kohonen
from sigmapi.rules.neighbourhood import GAUSSIAN, NEIGHBOURHOODS, Gaussian
from sigmapi.rules.ordering import ORDERINGS, Ordering, OrderingSettings
from sigmapi.rules.refinement import BATCH_MEAN, REFINEMENTS, BatchMean
from sigmapi.rules.winners import WINNER_RULES, Scoring, WinnerRule

__all__ = [
    "BATCH_MEAN",
    "GAUSSIAN",
    "KOHONEN",
    "LEARNING_RULES",
    "NEIGHBOURHOODS",
    "ORDERINGS",
    "REFINEMENTS",
    "WINNER_RULES",
    "BatchMean",
    "Gaussian",
    "Kohonen",
    "MapGeometry",
    "Ordering",
    "OrderingSettings",
    "Scoring",
    "WinnerRule",
    "lookup",
    "ordering",
    "winner_rule",
]

T = TypeVar("T")


def lookup(registry: Mapping[str, T], field: str, name: object) -> T:
    """The object called ``name`` in ``registry``; else a ConfigError naming ``field``, the
    value received and the choices.

    >>> lookup(WINNER_RULES, "winner_rule", "argmax")
    <winner rule 'argmax'>
    """
    _validate.choice(field, name, tuple(registry))
    return registry[name]  # type: ignore[index]  # a str: choice() found it among the keys


def winner_rule(rule: WinnerRule | str, field: str = "winner_rule") -> WinnerRule:
    """``rule`` itself if it is a :class:`WinnerRule`, else the registered rule of that name."""
    return rule if isinstance(rule, WinnerRule) else lookup(WINNER_RULES, field, rule)


def ordering(name: Ordering | str, field: str = "ordering") -> Ordering:
    """``name`` itself if it is an :class:`Ordering`, else the registered procedure of that
    name."""
    return name if isinstance(name, Ordering) else lookup(ORDERINGS, field, name)
