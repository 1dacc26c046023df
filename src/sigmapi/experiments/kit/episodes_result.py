"""The base of the results made of episode records per name, a state or a method (reach, robot,
reward), and the drawing of their learning curves (:func:`plot_with_bands`)."""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from sigmapi.agents import Episodes
from sigmapi.experiments.kit.episodes import final_rates, success_curve
from sigmapi.experiments.kit.figures import plot_apart
from sigmapi.experiments.kit.results import Result, _entry

if TYPE_CHECKING:
    from matplotlib.axes import Axes


@dataclass
class EpisodesResult(Result):
    """A result of episode records: ``success[name]``, ``lost[name]`` and ``steps[name]``, one
    row per seed of ``seeds``, say whether each episode succeeded, whether the world ended it
    without success (the rest timed out) and how many steps it took. The config's ``run`` part
    has ``block`` and ``final_episodes``. A result read back (:meth:`from_dict`) holds no
    records: its summaries are ``written``."""

    config: Any
    seeds: tuple[int, ...]
    success: dict[str, NDArray[np.bool_]] = field(default_factory=dict)
    lost: dict[str, NDArray[np.bool_]] = field(default_factory=dict)
    steps: dict[str, NDArray[np.int64]] = field(default_factory=dict)

    def __init_subclass__(cls, **kwargs: object) -> None:
        """:attr:`COMPUTED`, unless the class gives it: the keys of :attr:`KEYS` that no field
        gives (nor ``"config"``, nor a merged ``"*attribute"``, nor a key of :attr:`LATER`)."""
        super().__init_subclass__(**kwargs)
        if "COMPUTED" not in vars(cls):
            fields = {n for c in cls.__mro__ for n in inspect.get_annotations(c)}
            keys = [_entry(e) for e in cls.KEYS if not e.startswith("*")]
            cls.COMPUTED = tuple(
                k for k, attr in keys if attr not in fields and k not in ("config", *cls.LATER)
            )

    def record(self, name: str, episodes: Sequence[Episodes]) -> None:
        """Keep the records of ``name``: each seed's episodes, in the order of ``seeds``."""
        self.success[name] = np.stack([e.success for e in episodes])
        self.lost[name] = np.stack([e.failed for e in episodes])
        self.steps[name] = np.stack([e.steps for e in episodes])

    def window(self, key: str = "success") -> dict[str, NDArray[Any]]:
        """Per name, the records ``key`` (``"success"``, ``"lost"``, a record of the subclass)
        of the last ``final_episodes`` episodes, ``(len(seeds), final_episodes)``."""
        f = self.config.run.final_episodes
        return {s: r[:, -f:] for s, r in getattr(self, key).items()}

    def final(self, key: str = "success") -> dict[str, NDArray[np.float64]]:
        """Per name, the rate of the records ``key`` over the last ``final_episodes``
        episodes (:meth:`window`), one per seed."""
        return {s: final_rates(w, w.shape[1]) for s, w in self.window(key).items()}

    def final_mean(self, key: str = "success") -> dict[str, float]:
        """:meth:`final`, mean over seeds."""
        return {s: float(v.mean()) for s, v in self.final(key).items()}

    def final_share(self, key: str = "lost") -> dict[str, float]:
        """Per name, the share of the episodes of :meth:`window` (all seeds together) with
        the records ``key``."""
        return {s: float(w.mean()) for s, w in self.window(key).items()}

    def success_curves(self, extremes: bool = False) -> dict[str, dict[str, NDArray[np.float64]]]:
        """Per name, the learning curve of its success (:func:`.episodes.success_curve`:
        block ends, rate per block, mean and sd over seeds; with ``extremes``, min and max)."""
        b = self.config.run.block
        return {s: success_curve(r, b, extremes) for s, r in self.success.items()}


def plot_with_bands(
    ax: Axes,
    curves: Mapping[str, Mapping[str, Any]],
    key: str,
    band: Callable[[Mapping[str, Any]], tuple[Any, Any]],
    label: str,
    *,
    alpha: float = 0.15,
    **apart: Any,
) -> None:
    """Learning curves: each curve's ``key`` over its ``episode`` (:func:`.figures.plot_apart`
    with ``apart``, lines 1.8 wide) and its band, ``band(curve)`` (low, high), shaded in its
    colour; the bands share the label ``label`` (one entry: :func:`.figures.legend_once`)."""
    x = {s: list(c["episode"]) for s, c in curves.items()}
    plot_apart(ax, x, {s: list(c[key]) for s, c in curves.items()}, width=1.8, **apart)
    colours = apart.get("colours") or {}
    for i, (s, c) in enumerate(curves.items()):
        colour = colours.get(s) or f"C{i}"
        ax.fill_between(c["episode"], *band(c), color=colour, alpha=alpha, lw=0, label=label)


def sd_band(curve: Mapping[str, Any]) -> tuple[Any, Any]:
    """A curve's success minus and plus its standard deviation over seeds (a band of
    :func:`plot_with_bands`)."""
    m = np.asarray(curve["success"])
    sd = np.asarray(curve["success_sd"])
    return m - sd, m + sd
