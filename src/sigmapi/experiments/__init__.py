"""Experiments above the library: one protocol, a registry, a kit, one package per experiment.

:mod:`~sigmapi.experiments.base` holds the :class:`Experiment` protocol (an experiment writes
its ``execute(config, run)``, ``run`` a :class:`Run`), :data:`REGISTRY`, :func:`register`,
:func:`write_result` and :func:`check_seeds`; :mod:`~sigmapi.experiments.kit` what the
experiments share. Each experiment is a package named as its command (:data:`ENTRIES`) with
its ``run`` (robot's: ``variant``) and, where it has them apart, ``config``, ``result`` and
``figures`` (the small ones, chain, compare, stream and physiology, keep all in ``run``, read
top to bottom); its ``__init__`` names its guide and results page.

A new experiment is one package and one line in :data:`ENTRIES`; nothing here imports an
experiment until it is used (``sigmapi --help`` lists them from :data:`ENTRIES`).
"""

from __future__ import annotations

import importlib
from typing import Any

from sigmapi.experiments.base import (
    REGISTRY,
    Experiment,
    Result,
    Run,
    check_seeds,
    read_result,
    register,
    write_result,
)

# name, "module:object", one line for ``sigmapi --help``; left unformatted: one entry a row
ENTRIES = (
    ("chain", "sigmapi.experiments.chain.run:CHAIN",
     "a chain of two maps (retina -> head -> body) against one map on the whole task"),
    ("icub", "sigmapi.experiments.icub.run:ICUB",
     "the iCub learns a chain of maps from its eyes and neck, then learns to reach"),
    ("compare", "sigmapi.experiments.compare.run:COMPARE",
     "the Sigma-Pi map beside the baselines a user would pick instead"),
    ("neurons", "sigmapi.experiments.neurons.run:NEURONS",
     "the transformation in dendritic, basis-function and spiking neurons"),
    ("physiology", "sigmapi.experiments.physiology.run:PHYSIOLOGY",
     "read a model file's units as an electrophysiologist: reference frame, gain fields"),
    ("reach", "sigmapi.experiments.reach.run:REACH",
     "learn to reach with an actor-critic on the learned map vs. other states"),
    ("reproduce", "sigmapi.experiments.reproduce.run:REPRODUCE",
     "train the paper presets and write the report"),
    ("reward", "sigmapi.experiments.reward.run:REWARD",
     "a map whose plasticity is gated by reward vs. the frozen map and a shuffled control"),
    ("robot", "sigmapi.experiments.robot.variant:ROBOT",
     "a simulated robot learns the map from its own saccades, then docks on it"),
    ("stream", "sigmapi.experiments.stream.run:STREAM",
     "learning from a stream of frames (trace rule) against explicit view pairs"),
    ("sweep", "sigmapi.experiments.sweep.run:SWEEP",
     "train and evaluate a grid of parameters x seeds"),
)  # fmt: skip
"""The experiments of the package: one entry each (a new experiment is one line here)."""

for _entry in ENTRIES:
    REGISTRY.add(*_entry)

_LAZY_FROM = {
    "chain.run": ("run_chain",),
    "compare.run": ("CompareConfig", "CompareResult", "run_compare"),
    "kit.report": ("ReportContext", "Section"),
    "neurons.run": ("NEURONS", "NeuronsExperiment"),
    "physiology.run": ("PHYSIOLOGY", "PhysiologyExperiment"),
    "reach.run": ("REACH", "ReachExperiment"),
    "reproduce.results": ("ReproduceOptions", "ReproduceResult"),
    "reproduce.run": ("REFERENCE", "SECTIONS", "paper_presets"),
    "reward.run": ("REWARD", "RewardExperiment"),
    "robot.variant": ("ROBOT", "RobotExperiment"),
    "stream.run": ("STREAM", "StreamExperiment"),
    "sweep.run": ("SweepSpec", "run_sweep"),
}
_LAZY = {name: module for module, names in _LAZY_FROM.items() for name in names}
"""The names this package re-exports from its experiments, imported on first use."""


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        value = getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "ENTRIES",
    "REGISTRY",
    "Experiment",
    "Result",
    "Run",
    "check_seeds",
    "read_result",
    "register",
    "write_result",
    *_LAZY,  # imported on first use (__getattr__)
]
