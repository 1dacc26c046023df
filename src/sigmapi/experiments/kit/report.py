"""What an experiment adds to the report of ``sigmapi reproduce``: a :class:`Section`, made by
a function of the :class:`ReportContext` named by its ``"module:function"``
(:func:`section_function`), so that the report imports no experiment and an experiment no part
of the report."""

from __future__ import annotations

import importlib
import re
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

from sigmapi import _validate

if TYPE_CHECKING:
    from sigmapi.model.som import SigmaPiSOM


@dataclass(frozen=True)
class Section:
    """A section of the report."""

    title: str
    """Heading (plain text; escaped)."""
    html: str = ""
    """Body, an HTML fragment (trusted: write it with :func:`html.escape` on your values)."""
    figures: list[tuple[str, str]] = field(default_factory=list)
    """``(file name relative to the report folder, caption)`` per image; the files must exist
    when the report is written."""
    data: dict[str, object] = field(default_factory=dict)
    """Numbers to store in ``metrics.json`` under ``sections[title]``."""


class ReportOptions(Protocol):
    """The report's settings a section reads (the report's options have them)."""

    @property
    def quick(self) -> bool: ...
    @property
    def progress(self) -> bool: ...
    @property
    def workers(self) -> int | None: ...


@dataclass
class ReportContext:
    """What a section gets: the report folder, the run settings and the trained models
    (``models``: per preset name, one per seed in ``seeds`` order). Sections run in a thread of
    their own beside the report's figures and ceilings: a section draws holding ``drawing``,
    which the report holds while it draws its own."""

    out: Path
    options: ReportOptions
    models: dict[str, list[SigmaPiSOM]]
    drawing: threading.Lock = field(default_factory=threading.Lock, repr=False, compare=False)

    @property
    def quick(self) -> bool:
        return self.options.quick

    @property
    def progress(self) -> bool:
        return self.options.progress


SectionFn = Callable[[ReportContext], Section | None]
"""A function that adds a section to the report (None: it adds none)."""


def section_function(target: str | SectionFn) -> SectionFn:
    """The section function ``target`` names (``"module:function"``, imported now), or
    ``target`` itself if it is one."""
    if callable(target):
        return target
    if not isinstance(target, str) or not re.fullmatch(r"[\w.]+:\w+", target):
        raise _validate.fail(
            "report section",
            "'module:function' or a function",
            target,
            'e.g. "sigmapi.experiments.reach.section:reach_section"',
        )
    module, _, name = target.partition(":")
    fn: SectionFn = getattr(importlib.import_module(module), name)
    return fn
