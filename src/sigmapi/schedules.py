"""Schedules of the neighbourhood width sigma(t) and the learning rate eps(t).

Milestones are kept as *fractions of the run*, so that a schedule written for the paper's
300,000 iterations scales to any length: the paper's sigma goes linearly 8.0 -> 3.5 at 0.11
(iteration 33,000) -> 1e-5 at 2/3 (iteration 200,000), then stays constant.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sigmapi.errors import ConfigError

__all__ = ["PAPER_SIGMA", "PiecewiseLinear"]


@dataclass(frozen=True)
class PiecewiseLinear:
    """Piecewise-linear schedule through ``knots`` of (fraction of run, value).

    Before the first knot the first value holds, after the last knot the last value.
    A single knot gives a constant.

    Examples
    --------
    >>> s = PiecewiseLinear(((0.0, 8.0), (0.11, 3.5), (2 / 3, 1e-5)))
    >>> float(s.at(0, 300_000)), float(s.at(33_000, 300_000)), float(s.at(299_999, 300_000))
    (8.0, 3.5, 1e-05)
    """

    knots: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        try:
            knots = tuple((float(f), float(v)) for f, v in self.knots)
        except (TypeError, ValueError):
            raise ConfigError(
                f"schedule knots must be a list of [fraction, value] pairs, got {self.knots!r}; "
                "e.g. [[0.0, 8.0], [0.11, 3.5], [0.6667, 1e-5]]"
            ) from None
        if not knots:
            raise ConfigError(
                "schedule knots must hold at least one [fraction, value] pair, got []"
            )
        fr = np.array([f for f, _ in knots])
        vals = np.array([v for _, v in knots])
        if not (np.all(np.isfinite(fr)) and np.all(np.isfinite(vals))):
            raise ConfigError(f"schedule knots must be finite numbers, got {self.knots!r}")
        if np.any(fr < 0) or np.any(fr > 1) or np.any(np.diff(fr) <= 0):
            raise ConfigError(
                f"schedule fractions must rise strictly within [0, 1], got {fr.tolist()}; "
                "give milestones as fractions of the run"
            )
        object.__setattr__(self, "knots", knots)

    def at(self, t: int | NDArray[np.int64], total: int) -> NDArray[np.float64]:
        """Value at iteration(s) ``t`` of a run of ``total`` iterations."""
        xs = [round(f * total) for f, _ in self.knots]
        ys = [v for _, v in self.knots]
        return np.interp(np.asarray(t, dtype=np.float64), xs, ys)

    def to_list(self) -> list[list[float]]:
        return [[f, v] for f, v in self.knots]

    @classmethod
    def coerce(
        cls, value: PiecewiseLinear | float | Sequence[Sequence[float]], name: str
    ) -> PiecewiseLinear:
        """Accept a schedule, a constant, or a list of [fraction, value] pairs."""
        if isinstance(value, PiecewiseLinear):
            return value
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return cls(((0.0, float(value)),))
        try:
            return cls(tuple(tuple(k) for k in value))  # type: ignore[union-attr]
        except ConfigError as exc:
            raise ConfigError(f"{name}: {exc}") from None
        except TypeError:
            raise ConfigError(
                f"{name} must be a number or a list of [fraction, value] pairs, got {value!r}"
            ) from None


PAPER_SIGMA = PiecewiseLinear(((0.0, 8.0), (0.11, 3.5), (2.0 / 3.0, 1e-5)))
"""The neighbourhood width of the authors' 1-D script (8 -> 3.5 -> 1e-5 at 33k and 200k of 300k)."""
