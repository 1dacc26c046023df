"""The reproduce experiment (``sigmapi reproduce``): the paper presets trained and measured, and
the report.

Guide: docs/guide/reproduce.md; results: docs/results/reproduction.md.

Modules (``run`` holds the experiment object, ``REGISTRY``'s entry, and draws each preset's
figures): ``report_html``, ``results``, ``run``, ``training``.
"""
