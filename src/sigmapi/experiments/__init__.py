"""Experiments above the library: one protocol, a registry, and the experiments in it.

- :mod:`~sigmapi.experiments.base`: the :class:`Experiment` protocol, :data:`REGISTRY`,
  :func:`register`, :func:`write_result` (``result.json``) and :func:`check_seeds`;
- :mod:`~sigmapi.experiments.reproduce`: the experiment loop (presets x seeds);
- :mod:`~sigmapi.experiments.results`: its options and typed results, report sections;
- :mod:`~sigmapi.experiments.report_html`: the page;
- :mod:`~sigmapi.experiments.reach`: the gaze-and-reach learners (``sigmapi reach``), its
  config and result in ``reach_config`` / ``reach_result``, its report section in
  ``reach_section``;
- :mod:`~sigmapi.experiments.robot`: the simulated robot learns the map and docks on it
  (``sigmapi robot``), its config, map, result and figures in ``robot_config``,
  ``robot_map``, ``robot_result``, ``robot_plots``;
- :mod:`~sigmapi.experiments.reward`: a map whose plasticity is gated by reward against the
  frozen map and a shuffled-reward control (``sigmapi reward``), its config, result and
  figure in ``reward_config``, ``reward_result``, ``reward_plots``;
- :mod:`~sigmapi.experiments.sweep`: parameter and seed sweeps (``sigmapi sweep``);
- :mod:`~sigmapi.experiments.chain`: a chain of two maps (retina -> head -> body) against one;
- :mod:`~sigmapi.experiments.compare`: the Sigma-Pi map beside the baselines;
- :mod:`~sigmapi.experiments.stream`: maps learned from a stream of frames (the trace rule)
  against explicit pairs (``sigmapi stream``).
"""

from __future__ import annotations

import importlib
from typing import Any

from sigmapi.experiments.base import (
    REGISTRY,
    Experiment,
    Result,
    check_seeds,
    read_result,
    register,
    write_result,
)

# name, "module:object", one line for ``sigmapi --help``: the command line lists these
# without importing them; ``REGISTRY[name]`` imports the module when the command runs
ENTRIES = (
    ("chain", "sigmapi.experiments.chain:CHAIN",
     "a chain of two maps (retina -> head -> body) against one map on the whole task"),
    ("compare", "sigmapi.experiments.compare:COMPARE",
     "the Sigma-Pi map beside the baselines a user would pick instead"),
    ("reach", "sigmapi.experiments.reach:REACH",
     "learn to reach with an actor-critic on the learned map vs. other states"),
    ("reproduce", "sigmapi.experiments.reproduce:REPRODUCE",
     "train the paper presets and write the report"),
    ("reward", "sigmapi.experiments.reward:REWARD",
     "a map whose plasticity is gated by reward vs. the frozen map and a shuffled control"),
    ("robot", "sigmapi.experiments.robot:ROBOT",
     "a simulated robot learns the map from its own saccades, then docks on it"),
    ("stream", "sigmapi.experiments.stream:STREAM",
     "learning from a stream of frames (trace rule) against explicit view pairs"),
    ("sweep", "sigmapi.experiments.sweep:SWEEP",
     "train and evaluate a grid of parameters x seeds"),
)  # fmt: skip
"""The experiments of the package: one entry each (a new experiment is one line here)."""

for _entry in ENTRIES:
    REGISTRY.add(*_entry)

_LAZY = {
    "REACH": "reach",
    "ReachExperiment": "reach",
    "REFERENCE": "reproduce",
    "SECTIONS": "reproduce",
    "paper_presets": "reproduce",
    "REWARD": "reward",
    "RewardExperiment": "reward",
    "ROBOT": "robot",
    "RobotExperiment": "robot",
    "STREAM": "stream",
    "StreamExperiment": "stream",
    "SweepSpec": "sweep",
    "run_sweep": "sweep",
    "run_chain": "chain",
    "CompareConfig": "compare",
    "CompareResult": "compare",
    "run_compare": "compare",
    "ReportContext": "results",
    "ReproduceOptions": "results",
    "ReproduceResult": "results",
    "Section": "results",
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
    "REACH",
    "REFERENCE",
    "REGISTRY",
    "REWARD",
    "ROBOT",
    "SECTIONS",
    "STREAM",
    "CompareConfig",
    "CompareResult",
    "Experiment",
    "ReachExperiment",
    "ReportContext",
    "ReproduceOptions",
    "ReproduceResult",
    "Result",
    "RewardExperiment",
    "RobotExperiment",
    "Section",
    "StreamExperiment",
    "SweepSpec",
    "check_seeds",
    "paper_presets",
    "read_result",
    "register",
    "run_chain",
    "run_compare",
    "run_sweep",
    "write_result",
]
