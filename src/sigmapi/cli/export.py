"""``sigmapi export MODEL --format onnx --out FILE``: a trained map for callers outside Python
(:mod:`sigmapi.export`; docs/guide/export.md); ``--format nwb``: the map as a recorded brain
area in an NWB file (:mod:`sigmapi.nwb`; docs/guide/other-tools-nwb.md)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from sigmapi.cli._common import check_output, declare_path
from sigmapi.errors import UsageError, install_hint

__all__ = ["add_arguments", "cmd_export"]

FORMATS = ("onnx", "nwb")


def cmd_export(args: argparse.Namespace) -> int:
    if args.format not in FORMATS:  # argparse's choices say the same; kept for direct calls
        raise UsageError(f"--format must be one of {list(FORMATS)}, got {args.format!r}")
    if not Path(args.model).is_file():
        raise UsageError(
            f"model {args.model!r} does not exist or is not a file; give a model "
            "file written by `sigmapi train` or `sigmapi reproduce`"
        )
    out = check_output(args.out, args.force, "--out")
    if args.format == "nwb":
        return _export_nwb(args, out)
    from sigmapi.export import OPSET, export_onnx

    opset = OPSET if args.opset is None else args.opset
    export_onnx(args.model, out, opset=opset, inputs=args.inputs, force=True)
    print(f"wrote {out} ({out.stat().st_size:,} bytes)", file=sys.stderr)
    return 0


def _export_nwb(args: argparse.Namespace, out: Path) -> int:
    """``--format nwb``: :func:`sigmapi.nwb.export_nwb` (the ONNX options do not apply)."""
    if args.opset is not None or args.inputs != "codes":
        raise UsageError("--opset and --inputs apply to --format onnx only; drop them for nwb")
    from sigmapi.nwb import export_nwb

    export_nwb(args.model, out, force=True)
    print(f"wrote {out} ({out.stat().st_size:,} bytes)", file=sys.stderr)
    return 0


def add_arguments(p: Any) -> None:
    """Add ``sigmapi export``'s options and handler to its parser ``p`` (the command's line in
    :data:`sigmapi.cli.COMMANDS`)."""
    p.description = f"{p.description or ''} Needs the onnx extra: {install_hint('onnx')}.".strip()
    p.add_argument("model", help="model file written by `sigmapi train` or `sigmapi reproduce`")
    p.add_argument("--format", required=True, choices=FORMATS, help="file format (onnx, nwb)")
    p.add_argument("--out", required=True, help="file to write, e.g. map.onnx, map.nwb")
    p.add_argument("--opset", type=int, help="ONNX opset of the graph (default 21; 18 or later)")
    p.add_argument(
        "--inputs",
        choices=("codes", "positions"),
        default="codes",
        help="what the graph takes: the population codes x and y (default), or "
        "positions in [0, 1] that it encodes as the model does",
    )
    p.add_argument("--force", action="store_true", help="overwrite --out if it exists")
    declare_path(p, "model", "model", "input")
    declare_path(p, "out", "--out", "output")
    p.set_defaults(func=cmd_export)
