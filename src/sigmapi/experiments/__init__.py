"""Experiments above the library: the reproduction run, its HTML report, the reach section.

- :mod:`~sigmapi.experiments.reproduce`: the experiment loop (presets x seeds);
- :mod:`~sigmapi.experiments.results`: its options and typed results, report sections;
- :mod:`~sigmapi.experiments.report_html`: the page;
- :mod:`~sigmapi.experiments.reach_section`: the reach experiment as a report section;
- :mod:`~sigmapi.experiments.sweep`: parameter and seed sweeps (``sigmapi sweep``).
- :mod:`~sigmapi.experiments.chain`: a chain of two maps (retina -> head -> body) against one.
"""

from sigmapi.experiments.reproduce import REFERENCE, SECTIONS, paper_presets, reproduce
from sigmapi.experiments.results import ReportContext, ReproduceOptions, ReproduceResult, Section
from sigmapi.experiments.sweep import SweepSpec, run_sweep

__all__ = [
    "REFERENCE",
    "SECTIONS",
    "ReportContext",
    "ReproduceOptions",
    "ReproduceResult",
    "Section",
    "SweepSpec",
    "paper_presets",
    "reproduce",
    "run_sweep",
]
