"""Progress on stderr: bars (tqdm) on a terminal, plain lines in a log.

:func:`progress_callback` (training runs), :func:`counter` (counted work such as
episodes) and :func:`jobs_done` (parallel runs) return ``(callback, bar)``; use the bar as a
context manager so that it closes.
``disable=None`` draws a bar when stderr is a terminal and otherwise writes one line per phase
and one per finished run (``sigmapi reproduce > log 2>&1`` shows where it is);
``disable=True`` writes nothing. :class:`Progress` carries that choice into an experiment
(``progress=None``: nothing is written).

No open bar is silent for long: a heartbeat (:class:`Heartbeat`, one thread) redraws every
open bar on a terminal each second, and in a log writes a status line of every open bar
whenever no progress line has been written for :data:`HEARTBEAT_S` seconds: what is done, what
is left and an estimate of the time left from the throughput measured so far
(:meth:`Lines.status`), e.g. (``sigmapi icub --quick 2> log``, the phase last)::

    icub seed 0: 6 of 7 step after 1 min 27 s, 1 left, about 14 s more (0.069 step/s); test
    the reaches
"""

from __future__ import annotations

import os
import sys
import threading
import time
import weakref
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import Protocol, TypeVar

__all__ = [
    "HEARTBEAT_S",
    "Bar",
    "Heartbeat",
    "Lines",
    "Progress",
    "counter",
    "duration",
    "each",
    "jobs_done",
    "progress_callback",
]

T = TypeVar("T")


class Bar(Protocol):
    """What a bar offers its caller (a tqdm bar, or :class:`Lines` in a log)."""

    n: int

    def update(self, n: int) -> object: ...
    def set_postfix(self, *args: object, **kwargs: object) -> None: ...
    def set_postfix_str(self, phase: str, refresh: bool = True) -> None: ...
    def close(self) -> None: ...
    def __enter__(self) -> object: ...
    def __exit__(self, *exc: object) -> None: ...


class _Redrawn(Protocol):
    """A tqdm bar, as the heartbeat redraws it."""

    disable: bool

    def refresh(self) -> object: ...


R = TypeVar("R", bound=_Redrawn)


def _heartbeat_s() -> float:
    try:
        value = float(os.environ.get("SIGMAPI_HEARTBEAT_S", "20"))
    except ValueError:
        return 20.0
    return value if 0 < value < 1e6 else 20.0


HEARTBEAT_S = _heartbeat_s()
"""The longest a log goes without a progress line while a bar is open, in seconds: 20, or the
environment variable ``SIGMAPI_HEARTBEAT_S`` (a positive number; the promise to a user is
30 s: no command that runs is silent longer)."""


def duration(seconds: float) -> str:
    """``seconds`` as a person reads it: ``"45 s"``, ``"3 min 20 s"``, ``"1 h 05 min"``.

    Examples
    --------
    >>> duration(44.6), duration(200), duration(3900)
    ('45 s', '3 min 20 s', '1 h 05 min')
    """
    s = max(0, round(seconds))
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60:02d} s" if s % 60 else f"{s // 60} min"
    return f"{s // 3600} h {s % 3600 // 60:02d} min"


def _rate(per_s: float) -> str:
    return f"{per_s:,.0f}" if per_s >= 10 else f"{per_s:.2g}"


class Heartbeat:
    """The clock of the open bars: :meth:`beat` writes each open :class:`Lines`' status when
    no progress line has been written for ``period`` seconds, and redraws each open tqdm bar
    (its elapsed time and estimate move on a terminal while nothing is counted).

    One instance, :data:`HEART`, runs a daemon thread while any bar is open; a test gives
    its own ``clock`` and calls :meth:`beat` itself.
    """

    def __init__(
        self, period: float = HEARTBEAT_S, clock: Callable[[], float] = time.monotonic
    ) -> None:
        self.period, self.clock = period, clock
        self.last = clock()
        """When the last progress line was written."""
        self._open: weakref.WeakSet[_Redrawn | Lines] = weakref.WeakSet()
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None

    def wrote(self) -> None:
        """A progress line was just written: the silence starts again."""
        self.last = self.clock()

    def add(self, bar: _Redrawn | Lines, thread: bool = True) -> None:
        """Keep ``bar`` beating until :meth:`remove` (``thread``: start the thread if none)."""
        with self._lock:
            if not self._open:
                self.last = self.clock()
            self._open.add(bar)
            if thread and (self._thread is None or not self._thread.is_alive()):
                self._thread = threading.Thread(target=self._run, name="sigmapi-progress")
                self._thread.daemon = True
                self._thread.start()

    def remove(self, bar: _Redrawn | Lines) -> None:
        with self._lock:
            self._open.discard(bar)

    def beat(self) -> None:
        """Redraw the open bars; in a log, each one's status line if one is due."""
        with self._lock:
            bars = sorted(self._open, key=lambda b: getattr(b, "opened", 0.0))
        due = self.clock() - self.last >= self.period
        for bar in bars:
            if isinstance(bar, Lines):
                if due:
                    bar.status()
            elif bar.disable:  # a tqdm bar, closed
                self.remove(bar)
            else:
                bar.refresh()

    def _run(self) -> None:
        while True:
            time.sleep(min(1.0, self.period / 4))
            with self._lock:
                if not self._open:
                    self._thread = None
                    return
            try:
                self.beat()
            except Exception:  # pragma: no cover - a closed stream: progress is not the work
                return


HEART = Heartbeat()
"""The heartbeat of this process's bars."""


class _Trained(Protocol):
    """The model a training bar reads: its iteration count and its sigma."""

    @property
    def t_(self) -> int: ...
    @property
    def sigma_(self) -> float: ...


class Lines:
    """What a bar does, as plain lines: one per new phase, one when closed (count, time), and
    while open a status line (:meth:`status`) whenever the log has been silent for
    :data:`HEARTBEAT_S` seconds (:class:`Heartbeat`)."""

    def __init__(
        self, total: int, desc: str, unit: str, start: int = 0, heart: Heartbeat | None = None
    ) -> None:
        self.total, self.desc, self.unit, self.start, self.n = total, desc, unit, start, start
        self._phase = ""
        self._heart = HEART if heart is None else heart
        self._t0 = self.opened = self._heart.clock()
        self._closed = False
        self._heart.add(self, thread=heart is None)

    def _write(self, line: str) -> None:
        print(line, file=sys.stderr, flush=True)
        self._heart.wrote()

    def update(self, n: int) -> None:
        self.n += n

    def set_postfix(self, *args: object, **kwargs: object) -> None:
        pass

    def set_postfix_str(self, phase: str, refresh: bool = True) -> None:
        if phase and phase != self._phase:
            self._phase = phase
            self._write(f"{self.desc}: {phase}")

    def status(self) -> str:
        """Write, and return, where the bar is: done of total after the time so far, what is
        left and, once something is done, the time left at the throughput measured so far."""
        n, dt = self.n, self._heart.clock() - self._t0
        done, left = n - self.start, max(self.total - n, 0)
        unit = f" {self.unit}" if self.unit else ""
        line = f"{self.desc}: {n:,} of {self.total:,}{unit} after {duration(dt)}, {left:,} left"
        if done > 0 and dt > 0:
            per_s = done / dt
            rate = f" ({_rate(per_s)}{unit}/s)" if self.unit else ""
            line += f", about {duration(left / per_s)} more{rate}"
        else:
            line += ", no estimate before the first is done"
        if self._phase and not self._phase.startswith("["):
            line += f"; {self._phase}"
        self._write(line)
        return line

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        self._heart.remove(self)
        done, dt = self.n - self.start, self._heart.clock() - self._t0
        per_s = done / dt if dt > 0 else 0.0
        rate = f" ({_rate(per_s)} {self.unit}/s)" if dt > 0 and done > 0 and self.unit else ""
        unit = f" {self.unit}" if self.unit else ""
        self._write(f"{self.desc}: {done:,} of {self.total:,}{unit} in {dt:.1f} s{rate}")

    def __enter__(self) -> Lines:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _lines(disable: bool | None) -> bool:
    return disable is None and not (hasattr(sys.stderr, "isatty") and sys.stderr.isatty())


def _bar(total: int, desc: str, unit: str, start: int, disable: bool | None) -> Bar:
    from tqdm import tqdm

    if _lines(disable):
        return Lines(total, desc, unit, start)

    return _beating(
        tqdm(
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
    )


def _beating(bar: R) -> R:
    """``bar`` (a tqdm bar) redrawn by the heartbeat while it is open."""
    if not bar.disable:
        HEART.add(bar)
    return bar


def progress_callback(
    total: int, desc: str, start: int = 0, disable: bool | None = None
) -> tuple[Callable[[_Trained], None], Bar]:
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
) -> tuple[Callable[[int, str], None], Bar]:
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
    return _beating(tqdm(items, desc=desc, disable=disable, file=sys.stderr, leave=False))


def _each_line(items: list[T], desc: str) -> Iterator[T]:
    with Lines(len(items), desc, "") as lines:
        for item in items:
            yield item
            lines.update(1)


def jobs_done(
    total: int, desc: str, disable: bool = False
) -> tuple[Callable[[bool, str], None], Bar]:
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

    @property
    def logs(self) -> bool:
        """Whether it writes plain lines (enabled, stderr no terminal): lines of several
        processes can share the stream, bars cannot."""
        return _lines(self.disable)

    def training(
        self, total: int, desc: str, start: int = 0
    ) -> tuple[Callable[[_Trained], None], Bar]:
        """:func:`progress_callback`."""
        return progress_callback(total, desc, start, self.disable)

    def counter(self, total: int, desc: str, unit: str) -> tuple[Callable[[int, str], None], Bar]:
        """:func:`counter`."""
        return counter(total, desc, unit, self.disable)

    def each(self, items: Iterable[T], desc: str) -> Iterable[T]:
        """:func:`each`."""
        return each(items, desc, self.disable)

    def jobs(self, total: int, desc: str) -> tuple[Callable[[bool, str], None], Bar]:
        """:func:`jobs_done`."""
        return jobs_done(total, desc, disable=not self.enabled)

    def note(self, line: str) -> None:
        """One line on stderr (nothing when disabled)."""
        if self.enabled:
            print(line, file=sys.stderr, flush=True)
            HEART.wrote()
