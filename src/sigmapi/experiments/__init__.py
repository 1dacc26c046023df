"""Experiments above the library: the reproduction run, its HTML report, the reach section.

- :mod:`~sigmapi.experiments.reproduce`: the experiment loop (presets x seeds);
- :mod:`~sigmapi.experiments.results`: its options and typed results, report sections;
- :mod:`~sigmapi.experiments.report_html`: the page;
- :mod:`~sigmapi.experiments.reach_section`: the reach experiment as a report section.
"""

from sigmapi.experiments.reproduce import REFERENCE, SECTIONS, paper_presets, reproduce
from sigmapi.experiments.results import ReportContext, ReproduceOptions, ReproduceResult, Section

__all__ = [
    "REFERENCE",
    "SECTIONS",
    "ReportContext",
    "ReproduceOptions",
    "ReproduceResult",
    "Section",
    "paper_presets",
    "reproduce",
]
