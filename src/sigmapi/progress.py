"""Progress bars on stderr (tqdm): one for training runs, one for counted work such as episodes,
one for parallel jobs (a line per finished job when stderr is not a terminal).

Both return ``(callback, bar)``; use the bar as a context manager so that it closes.
``disable=None`` lets tqdm hide the bar when stderr is not a terminal.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any, Protocol, TypeVar

if TYPE_CHECKING:
    from tqdm import tqdm

__all__ = ["counter", "each", "jobs_done", "progress_callback"]

T = TypeVar("T")


class _Trained(Protocol):
    t_: int
    sigma_: float


def _bar(total: int, desc: str, unit: str, start: int, disable: bool | None) -> tqdm[Any]:
    from tqdm import tqdm

    return tqdm(total=total, initial=start, desc=desc, unit=unit, unit_scale=unit == "it",
                dynamic_ncols=True, file=sys.stderr, disable=disable, mininterval=0.5)  # fmt: skip


def progress_callback(
    total: int, desc: str, start: int = 0, disable: bool | None = None
) -> tuple[Callable[[Any], None], tqdm[Any]]:
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
) -> tuple[Callable[[int, str], None], tqdm[Any]]:
    """A bar of ``total`` units of work; ``callback(n, phase)`` adds ``n`` and shows ``phase``."""
    bar = _bar(total, desc, unit, 0, disable)

    def callback(n: int, phase: str) -> None:
        bar.set_postfix_str(phase, refresh=False)
        bar.update(n)

    return callback, bar


def each(items: Iterable[T], desc: str, disable: bool | None = None) -> Iterable[T]:
    """``items`` with a transient bar (it disappears when the loop ends)."""
    from tqdm import tqdm

    return tqdm(items, desc=desc, disable=disable, file=sys.stderr, leave=False)


def jobs_done(
    total: int, desc: str, disable: bool = False
) -> tuple[Callable[[bool, str], None], tqdm[Any]]:
    """A bar of ``total`` jobs; ``callback(ok, line)`` counts one finished job.

    On a terminal the bar shows jobs done, failed and left; when stderr is a file (a log),
    each finished job prints ``line`` instead, one line per job.
    """
    tty = sys.stderr.isatty()
    bar = _bar(total, desc, "run", 0, disable or not tty)
    done = failed = 0

    def callback(ok: bool, line: str) -> None:
        nonlocal done, failed
        done += 1
        failed += not ok
        bar.set_postfix_str(f"failed {failed}, left {total - done}", refresh=False)
        bar.update(1)
        if not tty and not disable:
            print(f"{desc}: [{done}/{total}] {line}", file=sys.stderr, flush=True)

    return callback, bar
