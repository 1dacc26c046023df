"""What the sub-commands share: the one-line-error parser, config flags, output checks."""

from __future__ import annotations

import argparse
import ast
import dataclasses
import difflib
import inspect
import itertools
import os
import re
import sys
import textwrap
import typing
from collections.abc import Callable, Collection, Mapping, Sequence
from pathlib import Path
from typing import Any, Literal, NoReturn

from sigmapi._outputs import check_folder
from sigmapi.config import (
    SOMConfig,
    apply_overrides,
    check_map_fits_task,
    load_config_file,
    load_preset,
)
from sigmapi.errors import ConfigError, UsageError
from sigmapi.kernels import BACKENDS

__all__ = [
    "LazyParser",
    "Parser",
    "add_config_flags",
    "add_dataclass_flags",
    "apply_set_flags",
    "check_output",
    "check_paths",
    "config_keys_help",
    "dataclass_values",
    "declare_path",
    "field_docs",
    "plain",
    "resolve_config",
]


def did_you_mean(word: str, choices: Collection[str]) -> str:
    """``"; did you mean X?"`` for the choice ``X`` closest to a mistyped ``word``, or ``""``.

    Examples
    --------
    >>> did_you_mean("--quik", ["--quick", "--quiet", "--out"])
    '; did you mean --quick?'
    """
    close = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f"; did you mean {close[0]}?" if close else ""


_CHOICE = re.compile(r"invalid choice: '(.*)' \(choose from (.*)\)$")


class Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:  # one line, exit 2, as argparse does, no usage dump
        m = _CHOICE.search(message)
        if m:  # a mistyped command or value: the closest one
            message += did_you_mean(m.group(1), re.findall(r"'([^']*)'", m.group(2)))
        self.exit(2, f"{self.prog}: error: {message}\n")

    def parse_known_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        """argparse's, but ``--set KEY VALUE`` (a space for the ``=``) is refused with the
        fix, not reported as an unrecognised argument ``VALUE``."""
        argv = list(sys.argv[1:] if args is None else args)
        flags = {s for a in self._actions if a.type is key_value for s in a.option_strings}
        for flag, key, value in zip(argv, argv[1:], argv[2:], strict=False):
            if flag == "--":
                break
            if flag in flags and "=" not in key and not value.startswith("-"):
                self.error(
                    f"{flag} takes KEY=VALUE as one word, got {flag} {key} {value}; "
                    f"write {flag} {key}={value}"
                )
        return super().parse_known_args(argv, namespace)


class LazyParser(Parser):
    """A sub-command's parser whose options ``fill(parser)`` adds when it is first used (its
    arguments parsed or its help shown): listing the commands imports none of their modules."""

    def __init__(self, *args: Any, fill: Callable[[Parser], None] | None = None, **kwargs: Any):
        super().__init__(*args, **kwargs)
        self._fill = fill

    def filled(self) -> LazyParser:
        """This parser with its options (added now if they are not yet)."""
        fill, self._fill = self._fill, None
        if fill is not None:
            fill(self)
        return self

    def parse_known_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        """The command's arguments; one it does not know is its mistake, reported with the
        command's name (``sigmapi neurons: error: ...``) and the closest option."""
        parsed, extras = super(LazyParser, self.filled()).parse_known_args(args, namespace)
        if extras:
            first = next((a for a in extras if a.startswith("-")), "")
            hint = did_you_mean(first.partition("=")[0], self._option_string_actions)
            self.error(f"unrecognized arguments: {' '.join(extras)}{hint}")
        return parsed, extras

    def format_help(self) -> str:
        return super(LazyParser, self.filled()).format_help()

    def format_usage(self) -> str:
        return super(LazyParser, self.filled()).format_usage()


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive int, got {text!r}")
    return value


MAX_VALUE = 4096
"""Longest ``KEY=VALUE`` a flag takes (a config value is far shorter)."""


def key_value(text: str) -> str:
    """A ``KEY=VALUE`` flag's text, checked: one line, at most :data:`MAX_VALUE` characters
    (a longer one is shown cut short)."""
    shown = repr(text[:60]) + ("..." if len(text) > 60 else "")
    if "=" not in text:
        raise argparse.ArgumentTypeError(
            f"must be KEY=VALUE, got {shown}; e.g. iterations=50000 (no space around the =)"
        )
    if len(text) > MAX_VALUE:
        raise argparse.ArgumentTypeError(
            f"must be KEY=VALUE of at most {MAX_VALUE} characters, got {len(text):,} "
            f"({shown}); put long values in a --config file"
        )
    if any(ord(c) < 32 or ord(c) == 127 for c in text):
        raise argparse.ArgumentTypeError(
            f"must be one line of KEY=VALUE without control characters (a newline?), got "
            f"{shown}; give one --set per value"
        )
    return text


def add_workers_flag(p: argparse.ArgumentParser | argparse._ArgumentGroup, what: str) -> None:
    """``--workers N``: how many ``what`` run at once (:func:`sigmapi.executor.plan_workers`)."""
    p.add_argument(
        "--workers",
        type=_positive_int,
        default=None,
        help=f"{what} at once (default: one per core, as many as fit in the memory "
        "budget, half the available memory; results do not depend on it)",
    )


DEFAULT_PRESET = "paper-1d"
"""The preset of ``sigmapi train`` without ``--preset``."""


def config_keys_help() -> str:
    """The config keys ``--set`` and ``--config`` take, each with the bounds declared on its
    :class:`~sigmapi.SOMConfig` field (:func:`sigmapi._validate.bounded`), as lines for a
    command's help."""
    fields = dataclasses.fields(SOMConfig)
    bounded = [(f.name, f.metadata["bounds"].describe()) for f in fields if "bounds" in f.metadata]
    others = [f.name for f in fields if "bounds" not in f.metadata]
    width = max(len(name) for name, _ in bounded)
    lines = ["config keys (--set KEY=VALUE, --config FILE) and their bounds:"]
    lines += [f"  {name:<{width}}  {text}" for name, text in bounded]
    rest = ", ".join(others)
    lines += textwrap.wrap(
        f"and {rest}: shapes (15 or 15x15), schedules (a value or [[fraction, value], ...]: eps "
        "in (0, 1], sigma in (0, 1e+06]) and a table of notes",
        width=78,
        initial_indent="  ",
        subsequent_indent="  ",
    )
    return "\n".join(lines)


def add_config_flags(p: argparse.ArgumentParser) -> None:
    """``--preset``, ``--config``, ``--set``, ``--seed`` and ``--backend``."""
    its = load_preset(DEFAULT_PRESET).iterations  # read, not restated: the preset may change
    p.add_argument(
        "--preset",
        default=DEFAULT_PRESET,
        help=f"preset name (default {DEFAULT_PRESET}: {its:,} iterations; see `sigmapi presets`)",
    )
    p.add_argument("--config", help="TOML file whose keys override the preset")
    p.add_argument(
        "--set",
        action="append",
        type=key_value,
        metavar="KEY=VALUE",
        help="override one config key, e.g. --set iterations=50000 (repeatable)",
    )
    p.add_argument("--seed", type=int, help="seed of all random streams (default: the config's)")
    p.add_argument(
        "--backend",
        choices=["auto", *BACKENDS],
        help="kernel backend (default: the config's, 'auto')",
    )


def resolve_config(args: argparse.Namespace) -> SOMConfig:
    """The config of ``--preset`` / ``--config`` / ``--set`` / ``--seed`` / ``--backend``."""
    cfg = load_preset(args.preset) if args.preset else SOMConfig()
    if getattr(args, "config", None):
        try:
            cfg = load_config_file(args.config, base=cfg)
        except ConfigError as exc:
            raise ConfigError(f"--config: {exc}") from None
    cfg = apply_set_flags(cfg, getattr(args, "set", None))
    if getattr(args, "seed", None) is not None:
        cfg = cfg.replace(seed=args.seed)
    if getattr(args, "backend", None):
        cfg = cfg.replace(backend=args.backend)
    try:
        return check_map_fits_task(cfg)
    except ConfigError as exc:  # a preset's shapes agree: --config set them
        raise ConfigError(f"--config: {exc}") from None


def apply_set_flags(cfg: SOMConfig, items: list[str] | None) -> SOMConfig:
    """``cfg`` with the ``--set key=value`` overrides; their errors name the flag."""
    try:
        return apply_overrides(cfg, list(items or []))
    except ConfigError as exc:
        raise ConfigError(f"--set: {exc}") from None


def check_output(path: str | Path, force: bool, what: str = "output file") -> Path:
    """Refuse to overwrite an existing ``path`` without ``--force``; the folder must exist."""
    p = Path(path)
    if str(path).endswith(("/", os.sep)) or p.is_dir():
        raise UsageError(
            f"{what} {str(path)!r} names a folder; give a file name, e.g. {str(p / 'model.npz')!r}"
        )
    if p.is_symlink():
        raise UsageError(
            f"{what} {str(p)!r} is a symbolic link; sigmapi never writes through "
            "one: remove it, or give another file name"
        )
    if p.exists() and not force:
        raise UsageError(f"{what} {str(p)!r} exists; pass --force to overwrite it")
    if p.exists() and p.is_dir():
        raise UsageError(f"{what} {str(p)!r} is a folder; give a file name")
    if p.exists() and not p.is_file():
        raise UsageError(f"{what} {str(p)!r} is not a regular file (a device?); give a file name")
    check_folder(p, f"{what} {str(p)!r}")
    return p


PATHS = "_paths"
"""The parser default that lists a command's file arguments: ``(dest, flag, role)``, role
``"input"``, ``"output"`` or ``"folder"`` (an output folder)."""


def declare_path(
    p: argparse.ArgumentParser | argparse._ArgumentGroup, dest: str, flag: str, role: str
) -> None:
    """Declare the argument ``dest`` (shown as ``flag``) of ``p`` a path of ``role``
    (:data:`PATHS`), which :func:`check_paths` compares before the command runs."""
    if role not in ("input", "output", "folder"):
        raise ValueError(f"a path's role is input, output or folder, got {role!r}")
    given = tuple(p._defaults.get(PATHS, ()))  # a group shares its parser's defaults
    p._defaults[PATHS] = (*given, (dest, flag, role))


def check_paths(args: argparse.Namespace) -> None:
    """Before every command (:func:`sigmapi.cli.main`): none of its outputs is one of its
    inputs (:func:`sigmapi._outputs.refuse_input_as_output`), ``--force`` or not."""
    from sigmapi._outputs import refuse_input_as_output

    given: list[tuple[str, str, str]] = []
    for dest, flag, role in getattr(args, PATHS, ()):
        value = getattr(args, dest, None)
        if isinstance(value, str) and value:  # given (an option left out is None)
            given.append((str(flag), value, str(role)))
    inputs = [(flag, value) for flag, value, role in given if role == "input"]
    outputs = [(flag, value, role == "folder") for flag, value, role in given if role != "input"]
    if inputs and outputs:
        refuse_input_as_output(outputs, inputs)


# ------------------------------------------------------------------ flags from a dataclass


def field_docs(cls: type) -> dict[str, str]:
    """The docstring under each field of dataclass ``cls`` (as written in its source)."""
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(cls)))
    except (OSError, TypeError):  # no source shipped: flags without help
        return {}
    body = tree.body[0].body if tree.body and isinstance(tree.body[0], ast.ClassDef) else []
    docs = {}
    for node, after in itertools.pairwise(body):
        if (
            isinstance(node, ast.AnnAssign)
            and isinstance(node.target, ast.Name)
            and isinstance(after, ast.Expr)
            and isinstance(after.value, ast.Constant)
            and isinstance(after.value.value, str)
        ):
            docs[node.target.id] = " ".join(after.value.value.split())
    return docs


def grid(text: str) -> tuple[int, ...]:
    """A grid such as ``8x8`` or ``10`` as a tuple of positive ints."""
    try:
        shape = tuple(int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected a grid such as 8x8 or 10, got {text!r}"
        ) from None
    if not shape or any(n < 1 for n in shape):
        raise argparse.ArgumentTypeError(f"grid sizes must be positive, got {text!r}")
    return shape


def _names(text: str) -> tuple[str, ...]:
    return tuple(s.strip() for s in text.split(",") if s.strip())


def _numbers(kind: type) -> Callable[[str], tuple[Any, ...]]:
    """A parser of comma-separated numbers of ``kind`` (``int`` or ``float``) such as ``1,2,4``."""

    def parse(text: str) -> tuple[Any, ...]:
        try:
            return tuple(kind(v) for v in text.split(",") if v.strip())
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected {kind.__name__}s separated by commas such as 1,2,4, got {text!r}"
            ) from None

    parse.__name__ = f"{kind.__name__}s"
    return parse


_ROLE = re.compile(r":(?:[a-z]+:)?[a-z]+:`(~?)([^`<]*?)\s*(?:<([^>]*)>)?`")
_LITERAL = re.compile(r"``([^`]+)``|`([^`]+)`")


def plain(text: str) -> str:
    """Docstring text as ``--help`` shows it: Sphinx roles and literals as plain words.

    ``:class:`~sigmapi.experiments.Chain``` becomes ``Chain``, ``:func:`f <sigmapi.f>``` ``f``,
    literals lose their quotes but a command line, which keeps one pair of backquotes as the
    hand-written help texts quote commands; runs of white space become one space.

    Examples
    --------
    >>> plain("see :func:`~sigmapi.metrics.evaluate` and ``ordering='none'``")
    "see evaluate and ordering='none'"
    >>> plain("a preset name (``sigmapi presets``)")
    'a preset name (`sigmapi presets`)'
    """

    def role(m: re.Match[str]) -> str:
        tilde, title, target = m.group(1), m.group(2).strip(), m.group(3)
        if target is not None and title:
            return title
        name = title or (target or "")
        return name.rsplit(".", 1)[-1] if tilde else name

    text = _ROLE.sub(role, text)

    def literal(m: re.Match[str]) -> str:
        body = m.group(1) or m.group(2)
        return f"`{body}`" if body.startswith("sigmapi ") else body

    text = _LITERAL.sub(literal, text)
    return " ".join(text.split())


def _help(text: str) -> str:
    """``text`` for argparse, which formats help with ``%``."""
    return plain(text).replace("%", "%%")


def _flag_kwargs(f: dataclasses.Field[Any], hint: Any) -> tuple[dict[str, Any], str]:
    """The argparse keyword arguments of a field of type ``hint``, and its default as written."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    simple = [a for a in (args or (hint,)) if a is not type(None)] if origin is not Literal else []
    default: Any = f.default
    shown = str(default)
    if f.metadata.get("repeat"):
        kwargs: dict[str, object] = {"action": "append", "metavar": f.metadata.get("metavar")}
        if f.metadata.get("metavar") == "KEY=VALUE":
            kwargs["type"] = key_value
        return kwargs, " ".join(map(str, default)) if default else "none"
    if origin is Literal:
        return {"type": type(args[0]), "choices": args}, shown
    kind: Callable[[str], Any]
    if origin is tuple and args == (int, Ellipsis) and f.metadata.get("sep") == ",":
        kind, joiner = _numbers(int), ","
    elif origin is tuple and args == (int, Ellipsis):
        kind, joiner = grid, "x"
    elif origin is tuple and args == (float, Ellipsis):
        kind, joiner = _numbers(float), ","
    elif origin is tuple and args == (str, Ellipsis):
        kind, joiner = _names, ","
    elif simple == [bool]:
        if default is not False:
            raise TypeError(f"a bool field becomes an on-switch; {f.name} must default to False")
        return {"action": "store_true"}, "off"
    elif len(simple) == 1 and simple[0] in (int, float, str):
        kind, joiner = simple[0], ""
    else:
        raise TypeError(f"no command-line type for a field of type {hint!r}")
    if joiner and isinstance(default, tuple):
        shown = joiner.join(map(str, default))
    return {"type": kind, "metavar": f.metadata.get("metavar", f.name.upper())}, shown


def add_dataclass_flags(
    p: argparse.ArgumentParser | argparse._ArgumentGroup,
    cls: type,
    aliases: Mapping[str, str] | None = None,
    skip: Collection[str] = (),
) -> None:
    """One option ``--field-name`` per field of dataclass ``cls``, its help the field's docstring.

    A field without a default is a positional argument. Options default to None (the field's
    own default applies); a bool field is an on-switch; a ``Literal`` field offers its values;
    ``tuple[int, ...]`` is written ``8x8`` (``1,2,4`` with metadata ``{"sep": ","}``),
    ``tuple[float, ...]`` ``0,0.5`` and ``tuple[str, ...]`` ``a,b``; a field with
    metadata ``{"repeat": True}`` is given once per value; a field with declared bounds
    (:func:`sigmapi._validate.bounded`) shows them. ``aliases`` adds a second spelling
    for a field (e.g. ``{"model_path": "--model"}``); fields in ``skip`` get no option. Values
    are not checked here: ``cls`` checks them when it is built (:func:`dataclass_values`).
    """
    hints = typing.get_type_hints(cls)
    docs = field_docs(cls)
    for f in dataclasses.fields(cls):
        if f.name in skip:
            continue
        kwargs, shown = _flag_kwargs(f, hints[f.name])
        text = _help(docs.get(f.name, f.name.replace("_", " ")))
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            kwargs.pop("metavar", None)
            p.add_argument(f.name, help=text, **kwargs)
            if "path" in f.metadata:
                declare_path(p, f.name, f.name, f.metadata["path"])
            continue
        flags = [f"--{f.name.replace('_', '-')}"]
        if aliases and f.name in aliases:
            flags.append(aliases[f.name])
        notes = []
        if "bounds" in f.metadata:  # declared beside the field (sigmapi._validate.bounded)
            notes.append(f.metadata["bounds"].describe())
        if f.default is not None:  # a None default is explained by the docstring
            notes.append(f"default {shown}")
        if notes:
            text = f"{text.removesuffix('.')} ({'; '.join(notes)})"
        p.add_argument(*flags, dest=f.name, default=None, help=text, **kwargs)
        if "path" in f.metadata:  # a file it reads or writes (sigmapi._outputs.INPUT)
            declare_path(p, f.name, flags[0], f.metadata["path"])


def dataclass_values(args: argparse.Namespace, cls: type) -> dict[str, object]:
    """The fields of ``cls`` given on the command line (the options left out are not listed);
    repeated values as a tuple."""
    given = ((f.name, getattr(args, f.name, None)) for f in dataclasses.fields(cls))
    return {name: tuple(v) if isinstance(v, list) else v for name, v in given if v is not None}
