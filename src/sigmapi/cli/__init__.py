"""The ``sigmapi`` command line: a thin front that maps flags onto the API's config objects.

Sub-commands: one per experiment of :data:`sigmapi.experiments.REGISTRY` (``chain``,
``compare``, ``reproduce``, ``sweep``, ...), generated with its options from the experiment's
config dataclass (:mod:`sigmapi.cli.experiment`); and the commands that are no experiment:
``train``, ``evaluate``, ``presets`` (:mod:`sigmapi.cli.train`, whose ``register(subparsers)``
adds their parsers) and those of :data:`COMMANDS` (``figure``: :mod:`sigmapi.cli.figure`;
``export``: :mod:`sigmapi.cli.export`), each a name, its one-line help and the
``"module:function"`` that adds its options. Every parser's
``func`` is a handler ``handler(args) -> int``. A command's options are added, and its modules
imported, only when it runs or its help is shown: ``sigmapi --help``, ``--version`` and
``presets`` import no experiment, nor numba, matplotlib, scikit-learn, MuJoCo or Dask.

A user mistake (unknown preset, bad value, missing file) prints one line to stderr and exits
with status 2; no traceback: every :class:`~sigmapi.errors.SigmapiError` is printed the same
way. Before any command runs, none of its outputs may be one of its inputs
(:func:`~sigmapi.cli._common.check_paths`: each command declares its file arguments).
"""

from __future__ import annotations

import argparse
import importlib
import signal
import sys
import threading
from collections.abc import Callable, Sequence

from sigmapi.cli import train
from sigmapi.cli._common import LazyParser, Parser, check_output, check_paths, resolve_config
from sigmapi.cli.experiment import add_experiment
from sigmapi.errors import SigmapiError
from sigmapi.experiments import REGISTRY

__all__ = ["COMMANDS", "build_parser", "check_output", "main", "resolve_config"]


# left unformatted: a table, one row per command
COMMANDS = (
    ("figure", "draw one figure of a trained model", "sigmapi.cli.figure:add_arguments"),
    ("export", "write a trained map as an ONNX graph (response, winner)",
     "sigmapi.cli.export:add_arguments"),
)  # fmt: skip
"""The commands that are no experiment, besides train / evaluate / presets: name, one line of
help, and ``"module:function"``, ``function(parser)`` adding the options and the handler; the
module is imported only when the command is used (a new command is one line here)."""


def _options(target: str) -> Callable[[Parser], None]:
    def fill(p: Parser) -> None:
        module, _, function = target.partition(":")
        getattr(importlib.import_module(module), function)(p)

    return fill


def build_parser() -> argparse.ArgumentParser:
    """The ``sigmapi`` parser with every sub-command; a command's options, and the modules
    they need, are added when it is used (:class:`~sigmapi.cli._common.LazyParser`), so that
    ``sigmapi --help`` and ``--version`` import no experiment."""
    from sigmapi._version import __version__

    parser = Parser(
        prog="sigmapi", description="Sigma-Pi self-organizing maps (Weber & Wermter 2007)"
    )
    parser.add_argument("--version", action="version", version=f"sigmapi {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=LazyParser)
    train.register(sub)
    for name, text, target in COMMANDS:
        sub.add_parser(name, help=text, fill=_options(target))
    for name in sorted(REGISTRY):
        add_experiment(sub, name, REGISTRY.entries[name].summary)
    for action in sub._choices_actions:  # `sigmapi CMD --help` opens with its one-line summary
        cmd = sub.choices[action.dest]
        if cmd.description is None and action.help:
            cmd.description = action.help[0].upper() + action.help[1:] + "."
    return parser


class Terminated(BaseException):
    """SIGTERM, turned into an exception so that ``finally`` blocks (temp files) run."""


def _terminate(signum: int, frame: object) -> None:
    raise Terminated


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``sigmapi`` command."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.default_int_handler)  # see sigmapi/__init__.py
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        previous = signal.signal(signal.SIGTERM, _terminate)
    except ValueError:  # not the main thread: leave signals alone
        previous = None
    try:
        check_paths(args)  # no command writes over its own input, --force or not
        return int(args.func(args))
    except Terminated:
        print(f"sigmapi {args.command}: terminated", file=sys.stderr)
        return 143
    except SigmapiError as exc:
        print(f"sigmapi {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # unwritable folder, disk full, ...: the user's environment
        where = f" {exc.filename!r}" if exc.filename else ""
        print(
            f"sigmapi {args.command}: error: cannot access{where}: {exc.strerror or exc}",
            file=sys.stderr,
        )
        return 2
    except KeyboardInterrupt:
        print(f"sigmapi {args.command}: interrupted", file=sys.stderr)
        return 130
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
