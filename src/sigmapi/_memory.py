"""Memory estimates checked before allocating: refuse what the machine cannot hold.

``check(need, what, fix)`` compares an estimate in bytes with the memory available now
(``MemAvailable`` of ``/proc/meminfo`` on Linux, else free physical pages) and raises
:class:`~sigmapi.errors.ResourceError` (a ``MemoryError``), or the class given, with the
estimate, what is available and the fix. Where neither is known, nothing is refused.
"""

from __future__ import annotations

import os

from sigmapi.errors import ResourceError

__all__ = ["available", "check", "check_count", "human"]


def available() -> int | None:
    """Bytes of memory available to a new allocation now, or None if unknown."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def human(n: float) -> str:
    """``n`` bytes as e.g. ``"1.5 GB"`` (powers of 1000)."""
    for unit in ("B", "kB", "MB", "GB", "TB", "PB"):
        if abs(n) < 1000 or unit == "PB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.3g} {unit}"
        n /= 1000
    raise AssertionError("unreachable")


def check(need: int, what: str, fix: str, error: type[Exception] = ResourceError) -> None:
    """Raise ``error`` if ``need`` bytes exceed the memory available now."""
    have = available()
    if have is not None and need > have:
        raise error(
            f"{what} needs about {human(need)} of memory, more than the {human(have)} "
            f"available on this machine; {fix}"
        )


def check_count(name: str, n: int, each: int, fix: str) -> None:
    """Raise :class:`~sigmapi.errors.ResourceError` if ``n`` items (a user-given size, the
    parameter ``name``) of ``each`` bytes exceed the memory available now."""
    check(int(n) * int(each), f"{name}={int(n):,}", fix)
