"""Imported first by ``sigmapi/__init__.py``: a quiet Ctrl-C while the command line starts.

When the process is the ``sigmapi`` command (the console script, or ``python -m
sigmapi.cli``), Ctrl-C during the package's imports (numpy, gymnasium, matplotlib: about
0.3 s) prints one line and exits with status 130 instead of a traceback.
:func:`sigmapi.cli.main` restores Python's own handler before it runs a command. Imported as a
library, nothing changes.
"""

from __future__ import annotations

import os
import signal
import sys

__all__ = ["is_command_line"]


def is_command_line() -> bool:
    """Whether this process is the ``sigmapi`` command starting up."""
    name = os.path.basename(sys.argv[0]) if sys.argv else ""
    return name == "sigmapi" or getattr(sys, "orig_argv", [])[1:3] == ["-m", "sigmapi.cli"]


def _interrupted(signum: int, frame: object) -> None:
    sys.stderr.write("sigmapi: interrupted\n")
    os._exit(130)  # nothing to clean up yet: only imports have run


if is_command_line():
    signal.signal(signal.SIGINT, _interrupted)


def check_thread_count() -> None:
    """``NUMBA_NUM_THREADS``, which numba reads when it is imported and rejects with a
    traceback unless it is an int >= 1, checked first: the command line says so in one line
    and exits with status 2; imported as a library, a ConfigError says it."""
    text = os.environ.get("NUMBA_NUM_THREADS")
    if text is None or not text.strip().lstrip("+-").isdigit() or int(text) >= 1:
        return  # unset, or not a number (numba ignores it, with a warning), or valid
    message = (
        f"NUMBA_NUM_THREADS must be an int >= 1, got {text[:40]!r}; unset it (numba then "
        "uses one thread per core) or set e.g. NUMBA_NUM_THREADS=4"
    )
    if is_command_line():
        sys.stderr.write(f"sigmapi: error: {message}\n")
        sys.exit(2)
    from sigmapi.errors import ConfigError

    raise ConfigError(message)


check_thread_count()
