"""The arithmetic of episode records, once: outcomes per seed and episode (a ``(seeds,
episodes)`` array of bools) as block rates, learning curves and rates over the final episodes."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi.envs import STATES
from sigmapi.errors import ConfigError


def block_rates(outcomes: NDArray[np.bool_], block: int) -> NDArray[np.float64]:
    """The rate of each block of ``block`` episodes per seed, ``(seeds, episodes // block)``
    (blocks ``[0, block)``, ``[block, 2 block)``, ...; a last, shorter block is left out).

    Examples
    --------
    >>> block_rates(np.array([[True, False, True, True, False]]), 2)
    array([[0.5, 1. ]])
    """
    n = outcomes.shape[1] // block
    rates = outcomes[:, : n * block].reshape(outcomes.shape[0], n, block).mean(axis=2)
    return np.asarray(rates, dtype=np.float64)


def block_ends(n_blocks: int, block: int) -> NDArray[np.float64]:
    """The episode that ends each block: ``block, 2 block, ...`` as floats."""
    return np.asarray((np.arange(n_blocks) + 1.0) * block, dtype=np.float64)


def success_curve(
    outcomes: NDArray[np.bool_], block: int, extremes: bool = False
) -> dict[str, NDArray[np.float64]]:
    """The learning curve of ``outcomes`` ``(seeds, episodes)``: ``episode`` (the block ends),
    ``success`` (each block's rate, mean over seeds) and ``success_sd`` (its standard
    deviation over seeds); with ``extremes``, ``success_min`` and ``success_max`` too.

    Examples
    --------
    >>> success_curve(np.array([[True, False, True, True], [False, False, True, True]]), 2)
    {'episode': array([2., 4.]), 'success': array([0.25, 1.  ]), 'success_sd': array([0.25, 0.  ])}
    """
    rate = block_rates(outcomes, block)
    out = {
        "episode": block_ends(rate.shape[1], block),
        "success": rate.mean(axis=0),
        "success_sd": rate.std(axis=0),
    }
    if extremes:
        out.update(success_min=rate.min(axis=0), success_max=rate.max(axis=0))
    return out


def final_rates(outcomes: NDArray[np.bool_], final: int) -> NDArray[np.float64]:
    """Each seed's rate over its last ``final`` episodes, ``(seeds,)``."""
    return np.asarray(outcomes[:, -final:].mean(axis=1), dtype=np.float64)


def check_episode_run(
    config: Any, names: str = "states", choices: tuple[str, ...] = STATES
) -> None:
    """The rules of a frozen config of an episode run (``episodes``, ``block``,
    ``final_episodes`` and the field ``names``, default ``states``): the final window and one
    block fit in the episodes, the names are distinct ones of ``choices`` (default
    :data:`~sigmapi.envs.STATES`; stored as a tuple)."""
    if config.final_episodes > config.episodes:
        raise ConfigError(
            f"final_episodes must be <= episodes ({config.episodes}), got {config.final_episodes}"
        )
    if config.block > config.episodes:
        raise ConfigError(
            f"block must be <= episodes ({config.episodes}), got {config.block}; "
            "a learning curve needs at least one full block"
        )
    given = tuple(getattr(config, names))
    if not given or any(s not in choices for s in given) or len(set(given)) != len(given):
        raise ConfigError(f"{names} must be distinct names from {choices}, got {given!r}")
    object.__setattr__(config, names, given)
