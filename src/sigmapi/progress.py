"""Progress on stderr: bars (tqdm) on a terminal, plain lines in a log.

:func:`progress_callback` (training runs), :func:`counter` (counted work such as
episodes) and :func:`jobs_done` (parallel runs) return ``(callback, bar)``; use the bar as a
context manager so that it closes.
``disable=None`` draws a bar when stderr is a terminal and otherwise writes one line per phase
and one per finished run (``sigmapi reproduce > log 2>&1`` shows where it is);
``disable=True`` writes nothing. :class:`Progress` carries that choice into an experiment
(``progress=None``: nothing is written).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, TypeVar

if TYPE_CHECKING:
    from tqdm import tqdm

__all__ = ["Lines", "Progress", "counter", "each", "jobs_done", "progress_callback"]

T = TypeVar("T")


class _Trained(Protocol):
    t_: int
    sigma_: float


class Lines:
    """What a bar does, as plain lines: one per new phase, one when closed (count, time)."""

    def __init__(self, total: int, desc: str, unit: str, start: int = 0) -> None:
        self.total, self.desc, self.unit, self.start, self.n = total, desc, unit, start, start
        self._phase = ""
        self._t0 = time.perf_counter()
        self._closed = False

    def update(self, n: int) -> None:
        self.n += n

    def set_postfix(self, *args: Any, **kwargs: Any) -> None:
        pass

    def set_postfix_str(self, phase: str, refresh: bool = True) -> None:
        if phase and phase != self._phase:
            self._phase = phase
            print(f"{self.desc}: {phase}", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        done, dt = self.n - self.start, time.perf_counter() - self._t0
        per_s = done / dt if dt > 0 else 0.0
        shown = f"{per_s:,.0f}" if per_s >= 10 else f"{per_s:.2g}"
        rate = f" ({shown} {self.unit}/s)" if dt > 0 and done > 0 and self.unit else ""
        unit = f" {self.unit}" if self.unit else ""
        print(
            f"{self.desc}: {done:,} of {self.total:,}{unit} in {dt:.1f} s{rate}",
            file=sys.stderr,
            flush=True,
        )

    def __enter__(self) -> Lines:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _lines(disable: bool | None) -> bool:
    return disable is None and not (hasattr(sys.stderr, "isatty") and sys.stderr.isatty())


def _bar(total: int, desc: str, unit: str, start: int, disable: bool | None) -> Any:
    from tqdm import tqdm

    if _lines(disable):
        return Lines(total, desc, unit, start)

    return tqdm(
        total=total,
        initial=start,
        desc=desc,
        unit=unit,
        unit_scale=unit == "it",
        dynamic_ncols=True,
        file=sys.stderr,
        disable=disable,
        mininterval=0.5,
    )


def progress_callback(
    total: int, desc: str, start: int = 0, disable: bool | None = None
) -> tuple[Callable[[Any], None], tqdm[Any] | Lines]:
    """A bar of training iterations showing iterations/s and the current sigma.

    The callback takes the model (``callback(model)``, as ``fit`` calls it).
    """
    bar = _bar(total, desc, "it", start, disable)

    def callback(model: _Trained) -> None:
        bar.update(model.t_ - bar.n)
        bar.set_postfix(sigma=f"{model.sigma_:.3g}", refresh=False)

    return callback, bar


def counter(
    total: int, desc: str, unit: str, disable: bool | None = None
) -> tuple[Callable[[int, str], None], tqdm[Any] | Lines]:
    """A bar of ``total`` units of work; ``callback(n, phase)`` adds ``n`` and shows ``phase``."""
    bar = _bar(total, desc, unit, 0, disable)

    def callback(n: int, phase: str) -> None:
        bar.set_postfix_str(phase, refresh=False)
        bar.update(n)

    return callback, bar


def each(items: Iterable[T], desc: str, disable: bool | None = None) -> Iterable[T]:
    """``items`` with a transient bar (it disappears when the loop ends), or in a log one
    line when the loop ends."""
    from tqdm import tqdm

    if _lines(disable):
        return _each_line(list(items), desc)
    return tqdm(items, desc=desc, disable=disable, file=sys.stderr, leave=False)


def _each_line(items: list[T], desc: str) -> Iterator[T]:
    with Lines(len(items), desc, "") as lines:
        for item in items:
            yield item
            lines.update(1)


def jobs_done(
    total: int, desc: str, disable: bool = False
) -> tuple[Callable[[bool, str], None], tqdm[Any] | Lines]:
    """A bar of ``total`` parallel jobs; ``callback(ok, line)`` counts one finished job.

    On a terminal the bar shows jobs done, failed and left; in a log each finished job
    writes ``line`` (numbered), and the end one line with the count and the time.
    """
    bar = _bar(total, desc, "run", 0, True if disable else None)
    done = failed = 0

    def callback(ok: bool, line: str) -> None:
        nonlocal done, failed
        done += 1
        failed += not ok
        if isinstance(bar, Lines):
            bar.set_postfix_str(f"[{done}/{total}] {line}")
        else:
            bar.set_postfix_str(f"failed {failed}, left {total - done}", refresh=False)
        bar.update(1)

    return callback, bar


@dataclass(frozen=True)
class Progress:
    """How an experiment shows where it is, on stderr: the bars and lines of this module.

    ``Progress()`` draws bars on a terminal and writes plain lines in a log;
    ``Progress(disable=True)`` (what :meth:`of` makes of ``None``) writes nothing.
    """

    disable: bool | None = None
    """None: bars on a terminal, lines in a log; True: nothing."""

    @staticmethod
    def of(progress: Progress | None) -> Progress:
        """``progress``, or the silent one for ``None``."""
        return progress if progress is not None else Progress(disable=True)

    @property
    def enabled(self) -> bool:
        return self.disable is not True

    def training(
        self, total: int, desc: str, start: int = 0
    ) -> tuple[Callable[[Any], None], tqdm[Any] | Lines]:
        """:func:`progress_callback`."""
        return progress_callback(total, desc, start, self.disable)

    def counter(
        self, total: int, desc: str, unit: str
    ) -> tuple[Callable[[int, str], None], tqdm[Any] | Lines]:
        """:func:`counter`."""
        return counter(total, desc, unit, self.disable)

    def each(self, items: Iterable[T], desc: str) -> Iterable[T]:
        """:func:`each`."""
        return each(items, desc, self.disable)

    def jobs(self, total: int, desc: str) -> tuple[Callable[[bool, str], None], tqdm[Any] | Lines]:
        """:func:`jobs_done`."""
        return jobs_done(total, desc, disable=not self.enabled)

    def note(self, line: str) -> None:
        """One line on stderr (nothing when disabled)."""
        if self.enabled:
            print(line, file=sys.stderr, flush=True)
