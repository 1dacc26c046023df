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
  against explicit pairs (``sigmapi stream``);
- :mod:`~sigmapi.experiments.neurons`: dendritic, basis-function and spiking neurons against
  the Sigma-Pi map (``sigmapi neurons``); :mod:`~sigmapi.experiments.physiology`: a model file
  read as an electrophysiologist reads a brain area (``sigmapi physiology``).
"""

from sigmapi.experiments.base import (
    REGISTRY,
    Experiment,
    Result,
    check_seeds,
    read_result,
    register,
    write_result,
)
from sigmapi.experiments.chain import run_chain
from sigmapi.experiments.compare import CompareConfig, CompareResult, run_compare
from sigmapi.experiments.neurons import NEURONS, NeuronsExperiment
from sigmapi.experiments.physiology import PHYSIOLOGY, PhysiologyExperiment
from sigmapi.experiments.reach import REACH, ReachExperiment
from sigmapi.experiments.reproduce import REFERENCE, SECTIONS, paper_presets, reproduce
from sigmapi.experiments.results import ReportContext, ReproduceOptions, ReproduceResult, Section
from sigmapi.experiments.reward import REWARD, RewardExperiment
from sigmapi.experiments.robot import ROBOT, RobotExperiment
from sigmapi.experiments.stream import STREAM, StreamExperiment
from sigmapi.experiments.sweep import SweepSpec, run_sweep

__all__ = [
    "NEURONS",
    "PHYSIOLOGY",
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
    "NeuronsExperiment",
    "PhysiologyExperiment",
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
    "reproduce",
    "run_chain",
    "run_compare",
    "run_sweep",
    "write_result",
]
