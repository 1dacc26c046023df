"""The settings of ``sigmapi stream``: the task, the dwell times and the trace constants."""

from __future__ import annotations

from dataclasses import dataclass, field

from sigmapi import _validate
from sigmapi.config import SOMConfig
from sigmapi.experiments.base import KEY_VALUES
from sigmapi.experiments.kit.maps import MapSpec

__all__ = ["QUICK", "StreamConfig"]


@dataclass(frozen=True)
class StreamConfig:
    """What ``sigmapi stream`` trains and scores."""

    preset: str = "paper-1d"
    """The task and the map's settings (a preset name; ``sigmapi presets``)."""
    overrides: tuple[str, ...] = field(default=(), metadata=KEY_VALUES)
    """``key=value`` changes to the preset, e.g. ``iterations=50000`` (one per change)."""
    dwells: tuple[int, ...] = field(
        default=(1, 2, 4, 8, 16),
        metadata=_validate.bounded("ints", 1, 100_000, fix="saccades per position", sep=","),
    )
    """Dwell times: saccades (frames) per object position."""
    traces: tuple[float, ...] = field(
        default=(0.0, 0.5),
        metadata=_validate.bounded(
            "numbers", 0, 1, hi_open=True, fix="trace constants, e.g. 0,0.5"
        ),
    )
    """Trace constants of the trace rule (0: the two-view rule on consecutive frames)."""
    n_test: int = field(
        default=10_000, metadata=_validate.bounded("int", 10, 1_000_000, fix="e.g. 10000")
    )
    """Test z's (and calibration z's) of the evaluation."""

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "overrides", tuple(self.overrides))
        if not self.dwells:
            raise _validate.fail(
                "dwells", "at least one dwell time", list(self.dwells), "e.g. --dwells 1,2,4,8,16"
            )
        dwells = [
            _validate.integer("dwells", d, 1, fix="saccades per position") for d in self.dwells
        ]
        set_(self, "dwells", tuple(sorted(set(dwells))))
        if not self.traces:
            raise _validate.fail(
                "traces", "at least one trace constant", list(self.traces), "e.g. --traces 0,0.5"
            )
        traces = {
            _validate.number(
                "traces",
                t,
                0.0,
                1.0,
                hi_open=True,
                fix="trace constants in [0, 1), e.g. --traces 0,0.5",
            )
            for t in self.traces
        }
        set_(self, "traces", tuple(sorted(traces)))
        _validate.check_fields(self)
        self.som_config  # noqa: B018 (an unknown preset or a bad override fails here, not later)

    @property
    def som_config(self) -> SOMConfig:
        """The preset with the overrides: the task and the map's settings."""
        return MapSpec(self.preset, self.overrides).config()


QUICK = StreamConfig(
    overrides=("iterations=20000", "refine_pairs=20000"),
    dwells=(1, 4, 16),
    traces=(0.0, 0.5),
    n_test=2000,
)
"""The quick look: a short run of the 1-D map, three dwell times, one seed."""
