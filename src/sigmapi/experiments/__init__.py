"""Experiments above the library: one protocol, a registry, a kit, one package per experiment.

- :mod:`~sigmapi.experiments.base`: the :class:`Experiment` protocol (an experiment writes its
  ``execute(config, run)``, ``run`` a :class:`Run`), :data:`REGISTRY` (names
  registered lazily: :data:`ENTRIES`), :func:`register`, :func:`write_result`
  (``result.json``) and :func:`check_seeds`;
- one package per experiment, each with its ``run`` (the experiment object and its run) and,
  where it has them apart, ``config``, ``result`` and ``figures`` (the small ones, chain,
  compare, stream and physiology, keep settings and result in ``run``, read top to bottom);
  its ``__init__`` names its guide and results page: :mod:`~sigmapi.experiments.reproduce`
  (the report: also ``results`` and ``report_html``), :mod:`~sigmapi.experiments.sweep`,
  :mod:`~sigmapi.experiments.compare`,
  :mod:`~sigmapi.experiments.chain`, :mod:`~sigmapi.experiments.stream`,
  :mod:`~sigmapi.experiments.reach` (also ``section``, its part of the report),
  :mod:`~sigmapi.experiments.robot` (reach in the robot's world: ``variant``, ``map``),
  :mod:`~sigmapi.experiments.reward`,
  :mod:`~sigmapi.experiments.icub`, :mod:`~sigmapi.experiments.neurons` and
  :mod:`~sigmapi.experiments.physiology`.

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

# name, "module:object", one line for ``sigmapi --help``: the command line lists these
# without importing them; ``REGISTRY[name]`` imports the module when the command runs
# left unformatted: a table, one entry per experiment
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

_LAZY = {
    "REACH": "reach.run",
    "ReachExperiment": "reach.run",
    "REFERENCE": "reproduce.run",
    "SECTIONS": "reproduce.run",
    "paper_presets": "reproduce.run",
    "REWARD": "reward.run",
    "RewardExperiment": "reward.run",
    "ROBOT": "robot.variant",
    "NEURONS": "neurons.run",
    "NeuronsExperiment": "neurons.run",
    "PHYSIOLOGY": "physiology.run",
    "PhysiologyExperiment": "physiology.run",
    "RobotExperiment": "robot.variant",
    "STREAM": "stream.run",
    "StreamExperiment": "stream.run",
    "SweepSpec": "sweep.run",
    "run_sweep": "sweep.run",
    "run_chain": "chain.run",
    "CompareConfig": "compare.run",
    "CompareResult": "compare.run",
    "run_compare": "compare.run",
    "ReportContext": "kit.report",
    "ReproduceOptions": "reproduce.results",
    "ReproduceResult": "reproduce.results",
    "Section": "kit.report",
}
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
