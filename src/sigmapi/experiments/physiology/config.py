"""The settings of ``sigmapi physiology`` (:class:`PhysiologyConfig`)."""

from __future__ import annotations

from dataclasses import dataclass, field

from sigmapi import _validate
from sigmapi._outputs import INPUT
from sigmapi.analysis.monkey import EYE_GRID, N_RETINA, RESPONDS
from sigmapi.analysis.physiology import GAZES, check_gaze_axes

__all__ = ["PhysiologyConfig"]


@dataclass(frozen=True)
class PhysiologyConfig:
    """What ``sigmapi physiology`` records."""

    model: str = field(metadata=INPUT)
    """The model file to record from (``sigmapi train --out FILE``)."""
    gazes: tuple[float, ...] = field(
        default=GAZES,
        metadata=_validate.bounded("numbers", 0, 1, fix="fractions of the gaze axis", sep=","),
    )
    """Gaze directions (fractions of the gaze axis) the units are recorded at."""
    n_probe: int = field(
        default=0, metadata=_validate.bounded("int", 0, 1001, fix="0 for the default, e.g. 61")
    )
    """Probe positions along the swept retinal axis (0: 61; 15 along any other)."""
    tuning_units: int = field(default=3, metadata=_validate.bounded("int", 1, 10, fix="e.g. 3"))
    """Units whose tuning curves the figure shows."""
    body_slope: tuple[float, ...] = field(
        default=(),
        metadata=_validate.bounded("numbers", -100, 100, count=3, fix="e.g. -1", sep=","),
    )
    """How far a body-centred receptive field moves on the retina per unit of gaze, one value
    or one per gaze axis (empty: from the model's relation, -1 for z = (x + y) / 2). A map
    learned from a world of its own geometry needs that world's: the robot's and the iCub's
    are measured by ``benchmarks/bench_physiology.py --robot`` and ``--icub``."""
    gaze_axes: tuple[int, ...] = field(
        default=(),
        metadata=_validate.bounded("ints", 0, 2, count=3, fix="e.g. --gaze-axes 1,0", sep=","),
    )
    """For each retinal axis, the gaze axis that moves the receptive fields along it (empty:
    the same axis). The iCub's retina is (horizontal, vertical) and its gaze codes (tilt,
    pan): ``1,0``."""

    eye_grid: tuple[float, ...] = field(
        default=EYE_GRID,
        metadata=_validate.bounded(
            "numbers", 0, 1, count=21, fix="fractions of the gaze axis", sep=","
        ),
    )
    """The monkey protocol's eye positions along each gaze axis (every combination is a
    fixation; ``0.3,0.5,0.7``: the studies' 3 x 3 grid)."""
    n_retina: int = field(
        default=N_RETINA, metadata=_validate.bounded("int", 5, 101, fix=f"e.g. {N_RETINA}")
    )
    """The monkey protocol's stimulus positions along each retinal axis."""
    responds: float = field(
        default=RESPONDS, metadata=_validate.bounded("number", 0, 1, fix=f"e.g. {RESPONDS}")
    )
    """The monkey protocol counts a field at a fixation where the unit's best response there
    is at least this share of its best at any fixation."""
    nwb: bool = False
    """Also write the recording as an NWB file, physiology.nwb, into --out (needs the nwb
    extra: pip install 'sigmapi[nwb]')."""

    def __post_init__(self) -> None:
        if not isinstance(self.model, str) or not self.model:
            raise _validate.fail(
                "model", "a model file path", self.model, "e.g. sigmapi physiology model.npz"
            )
        _validate.check_fields(self)  # the bounds declared beside the fields
        gazes = list(self.gazes)
        if len(set(gazes)) < 3:
            raise _validate.fail(
                "gazes",
                "at least 3 distinct gazes",
                list(self.gazes),
                "e.g. --gazes 0.2,0.35,0.5,0.65,0.8",
            )
        object.__setattr__(self, "gazes", tuple(sorted(set(gazes))))
        if 0 < self.n_probe < 5:
            raise _validate.fail("n_probe", "0 or at least 5", self.n_probe, "e.g. 61")
        slopes = self.body_slope
        if any(v == 0.0 for v in slopes):
            raise _validate.fail("body_slope", "nonzero", list(slopes), "e.g. -1")
        object.__setattr__(self, "body_slope", slopes)
        axes = tuple(self.gaze_axes)  # the model's dimension is checked where it is loaded
        check_gaze_axes(axes, len(axes), "e.g. --gaze-axes 1,0")
        object.__setattr__(self, "gaze_axes", axes)
        grid = list(self.eye_grid)
        if len(set(grid)) < 3:
            raise _validate.fail(
                "eye_grid", "at least 3 distinct eye positions", list(self.eye_grid),
                "e.g. --eye-grid 0.3,0.5,0.7",
            )  # fmt: skip
        object.__setattr__(self, "eye_grid", tuple(sorted(set(grid))))
        _validate.boolean("nwb", self.nwb)
