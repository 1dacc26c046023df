"""``sigmapi export MODEL --format FORMAT --out FILE``: a trained map for other tools: an ONNX
graph (:mod:`sigmapi.export`; docs/guide/export.md), the map as a recorded brain area in an NWB
file (:mod:`sigmapi.nwb`; docs/guide/other-tools-nwb.md) or a NIR graph of spiking neurons
(:mod:`sigmapi.neurons.nir_graph`; docs/guide/other-tools.md).

A format is one entry of :data:`WRITERS`: a function that writes the model file ``args.model``
to ``out`` (checked, free to overwrite) and refuses options that are not its own."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from sigmapi.cli._common import check_output, declare_path
from sigmapi.errors import UsageError, install_hint

__all__ = ["add_arguments", "cmd_export"]


def _onnx(args: argparse.Namespace, out: Path) -> None:
    from sigmapi.export import OPSET, export_onnx

    opset = OPSET if args.opset is None else args.opset
    export_onnx(args.model, out, opset=opset, inputs=args.inputs, force=True)


def _nwb(args: argparse.Namespace, out: Path) -> None:
    """:func:`sigmapi.nwb.export_nwb` with the spikes of the spiking deployment where it runs
    (:func:`sigmapi.neurons.spiking.protocol_spikes`; the ONNX options do not apply)."""
    _only_onnx(args, "nwb")
    from sigmapi.neurons.spiking import protocol_spikes
    from sigmapi.nwb import export_nwb

    export_nwb(args.model, out, force=True, spikes=protocol_spikes)


def _nir(args: argparse.Namespace, out: Path) -> None:
    """:func:`sigmapi.neurons.nir_graph.export_nir` (the ONNX options do not apply)."""
    _only_onnx(args, "nir")
    from sigmapi.neurons.nir_graph import export_nir

    export_nir(args.model, out, force=True)


def _only_onnx(args: argparse.Namespace, fmt: str) -> None:
    """Refuse the ONNX graph's options for another format."""
    for flag, value, default in (("--opset", args.opset, None), ("--inputs", args.inputs, "codes")):
        if value != default:
            raise UsageError(f"{flag} applies to --format onnx only, not {fmt}; leave it out")


WRITERS: dict[str, Callable[[argparse.Namespace, Path], None]] = {
    "onnx": _onnx,
    "nwb": _nwb,
    "nir": _nir,
}
"""Each format's writer (a new format: one function and one entry here)."""

FORMATS = tuple(WRITERS)


def cmd_export(args: argparse.Namespace) -> int:
    if args.format not in WRITERS:  # argparse's choices say the same; kept for direct calls
        raise UsageError(f"--format must be one of {list(FORMATS)}, got {args.format!r}")
    if not Path(args.model).is_file():
        raise UsageError(
            f"model {args.model!r} does not exist or is not a file; give a model "
            "file written by `sigmapi train` or `sigmapi reproduce`"
        )
    out = check_output(args.out, args.force, "--out")
    WRITERS[args.format](args, out)
    print(f"wrote {out} ({out.stat().st_size:,} bytes)", file=sys.stderr)
    return 0


def add_arguments(p: Any) -> None:
    """Add ``sigmapi export``'s options and handler to its parser ``p`` (the command's line in
    :data:`sigmapi.cli.COMMANDS`)."""
    p.description = (
        f"{p.description or ''} Needs the onnx extra: {install_hint('onnx')}. "
        "--format nwb needs the nwb extra instead, --format nir the nir extra."
    ).strip()
    p.add_argument("model", help="model file written by `sigmapi train` or `sigmapi reproduce`")
    p.add_argument(
        "--format",
        required=True,
        choices=FORMATS,
        help="file format: onnx (the map's responses and winner, for onnxruntime), nwb (the map "
        "as a recorded area, for pynwb) or nir (the map as spiking neurons, for Norse, "
        "snnTorch, Rockpool, ...)",
    )
    p.add_argument("--out", required=True, help="file to write, e.g. map.onnx, map.nwb, map.nir")
    p.add_argument("--opset", type=int, help="onnx: opset of the graph (default 21; 18 or later)")
    p.add_argument(
        "--inputs",
        choices=("codes", "positions"),
        default="codes",
        help="onnx: what the graph takes: the population codes x and y (default), or "
        "positions in [0, 1] that it encodes as the model does",
    )
    p.add_argument("--force", action="store_true", help="overwrite --out if it exists")
    declare_path(p, "model", "model", "input")
    declare_path(p, "out", "--out", "output")
    p.set_defaults(func=cmd_export)
