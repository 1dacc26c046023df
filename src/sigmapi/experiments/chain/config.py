"""The settings of ``sigmapi chain``: the preset every map starts from, and the data of maps B
and single."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal, get_args

from sigmapi import _validate
from sigmapi.config import SOMConfig
from sigmapi.errors import ConfigError
from sigmapi.experiments.base import KEY_VALUES
from sigmapi.experiments.kit.maps import MapSpec

__all__ = ["CODES", "ChainConfig", "Code", "chain_config"]


Code = Literal["response", "winner"]


CODES: tuple[str, ...] = get_args(Code)
"""What map A hands to map B: its normalised response, or a code of its winner's position."""


def chain_config(config: SOMConfig | None = None, iterations: int | None = None) -> SOMConfig:
    """The config every map of the comparison starts from (default: paper-1d, unrefined).

    It must be 1-D (``map_shape``, ``x_shape`` and ``y_shape`` of one axis), non-periodic,
    with the ``mean`` relation; map A uses it as it is.
    """
    cfg = (
        config if config is not None else MapSpec("paper-1d", changes={"refine_rounds": 0}).config()
    )
    if not isinstance(cfg, SOMConfig):
        raise _validate.fail(
            "config",
            "a sigmapi.SOMConfig or None",
            type(cfg).__name__,
            "load a preset with sigmapi.load_preset(name)",
        )
    for name in ("map_shape", "x_shape", "y_shape"):
        if len(getattr(cfg, name)) != 1:
            raise _validate.fail(
                f"config.{name}",
                "1-D (one axis)",
                getattr(cfg, name),
                "the chain of frames is built on 1-D positions, e.g. (15,)",
            )
    if cfg.periodic or cfg.relation != "mean":
        raise ConfigError(
            f"config must be non-periodic with relation 'mean', got periodic={cfg.periodic}, "
            f"relation={cfg.relation!r}; the chain composes two means: a = (x + e) / 2, "
            "z = (a + u) / 2"
        )
    if iterations is not None:
        cfg = cfg.replace(iterations=_validate.integer("iterations", iterations, 1))
    return cfg


@dataclass(frozen=True)
class ChainConfig:
    """What ``sigmapi chain`` trains: the preset of every map and the data of maps B and single."""

    preset: str = "paper-1d"
    """The 1-D preset every map starts from (``sigmapi presets``), with sigmapi's ordering
    procedure (``crossview``) and no refinement (``refine_rounds=0``, the setting
    docs/results/chain.md measures; an override can turn it on)."""
    overrides: tuple[str, ...] = field(default=(), metadata=KEY_VALUES)
    """``key=value`` changes to the preset, e.g. ``iterations=50000`` (one per change)."""
    train_pairs: int = field(
        default=20_000, metadata=_validate.bounded("int", 10, 10_000_000, fix="e.g. 20000")
    )
    """View pairs of triples that map B and the single map are trained on."""
    n_test: int = field(
        default=10_000, metadata=_validate.bounded("int", 10, 1_000_000, fix="e.g. 10000")
    )
    """Calibration and test triples (each), from the fixed evaluation seed."""
    code: Code = "response"
    """What map A hands to map B: its normalised response, or a code of its winner's position."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "overrides", tuple(self.overrides))
        _validate.check_fields(self)
        _validate.choice("code", self.code, CODES)
        self.som_config  # noqa: B018 (an unknown preset or a bad override fails here, not later)

    @property
    def som_config(self) -> SOMConfig:
        """The preset with ``ordering="crossview"``, ``refine_rounds=0`` and the overrides
        (:func:`chain_config`)."""
        spec = MapSpec(self.preset, self.overrides, {"ordering": "crossview", "refine_rounds": 0})
        return chain_config(spec.config())
