"""The per-seed job of an experiment and its progress: one function, run where the executor
puts it, that shows a bar of its episodes only where it runs in the caller's process."""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

from sigmapi.progress import Progress

__all__ = ["Tick", "counted"]

T = TypeVar("T")

Tick = Callable[[int, str], None]
"""``tick(n, phase)``: ``n`` episodes just finished (0 while the map learns), and what runs."""


def counted(show: Progress | None, total: int, desc: str, work: Callable[[Tick | None], T]) -> T:
    """``work(tick)`` with a bar of ``total`` episodes named ``desc`` where ``show`` is given
    (the job runs in the caller's process, :func:`~sigmapi.experiments.base.run_all`'s
    ``verbose``), else ``work(None)``."""
    if show is None:
        return work(None)
    tick, bar = show.counter(total, desc, "ep")
    with bar:
        return work(tick)
