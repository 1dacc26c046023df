"""What the sub-commands share: the one-line-error parser, config flags, output checks."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import NoReturn

from sigmapi.config import SOMConfig, apply_overrides, load_config_file, load_preset
from sigmapi.errors import UsageError
from sigmapi.kernels import BACKENDS

__all__ = ["Parser", "add_config_flags", "check_output", "resolve_config"]


class Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:  # one line, exit 2, as argparse does, no usage dump
        self.exit(2, f"{self.prog}: error: {message}\n")


def add_config_flags(p: argparse.ArgumentParser) -> None:
    """``--preset``, ``--config``, ``--set``, ``--seed`` and ``--backend``."""
    p.add_argument("--preset", default="paper-1d", help="preset name (see `sigmapi presets`)")
    p.add_argument("--config", help="TOML file whose keys override the preset")
    p.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="override one config key, e.g. --set iterations=50000 (repeatable)",
    )
    p.add_argument("--seed", type=int, help="seed of all random streams (default: the config's)")
    p.add_argument("--backend", choices=["auto", *BACKENDS],
                   help="kernel backend (default: the config's, 'auto')")  # fmt: skip


def resolve_config(args: argparse.Namespace) -> SOMConfig:
    """The config of ``--preset`` / ``--config`` / ``--set`` / ``--seed`` / ``--backend``."""
    cfg = load_preset(args.preset) if args.preset else SOMConfig()
    if getattr(args, "config", None):
        cfg = load_config_file(args.config, base=cfg)
    cfg = apply_overrides(cfg, list(getattr(args, "set", None) or []))
    if getattr(args, "seed", None) is not None:
        cfg = cfg.replace(seed=args.seed)
    if getattr(args, "backend", None):
        cfg = cfg.replace(backend=args.backend)
    return cfg


def check_output(path: str | Path, force: bool, what: str = "output file") -> Path:
    """Refuse to overwrite an existing ``path`` without ``--force``; the folder must exist."""
    p = Path(path)
    if p.exists() and not force:
        raise UsageError(f"{what} {str(p)!r} exists; pass --force to overwrite it")
    if p.exists() and p.is_dir():
        raise UsageError(f"{what} {str(p)!r} is a folder; give a file name")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise UsageError(
            f"folder {str(parent)!r} of {what} {str(p)!r} does not exist; create it first"
        )
    return p
