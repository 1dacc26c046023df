"""A trained map as an ONNX graph, for callers outside Python (a controller in C++, a robot's
computer): :func:`export_onnx`, ``sigmapi export MODEL --format onnx --out FILE``.

The graph takes the two codes and gives what the model gives in Python:

- inputs ``x`` ``(B, n_x)`` and ``y`` ``(B, n_y)``, float64: the population codes of the
  retinal positions and gaze directions, flattened in C order, exactly as
  ``model.x_code.encode(p)`` and ``model.y_code.encode(p)`` make them (the codes' parameters
  are in the file's metadata, key ``sigmapi.x_code`` and ``sigmapi.y_code``; the formula is
  in docs/guide/export.md); or, with ``inputs="positions"``, ``x_position`` ``(B, d_x)``
  and ``y_position`` ``(B, d_y)`` in [0, 1], which the graph encodes itself;
- outputs ``response`` ``(B, n_units)`` float64, ``h[b, k] = x_b^T W_k y_b``
  (:meth:`~sigmapi.SigmaPiSOM.respond`), and ``winner`` ``(B,)`` int64, the flat index of the
  winning unit as :meth:`~sigmapi.SigmaPiSOM.winner` computes it: the model's winner rule at
  its current sigma (the soft rule's smoothing over the map, bounded or periodic, is a fixed
  ``(n_units, n_units)`` matrix at that sigma), ties to the lowest index.

The fast kernel skips the code pairs with ``|x_i y_j| <= kernel_tol max|x| max|y|``; the graph
skips the same pairs, so that its winners are the kernel's, and like the kernel it reads only
the weight rows of the pairs it keeps (a ``Scan`` over the batch, one pair at a time: about
1,000-1,300 of the paper-2d map's 50,625 rows per pair), not the whole matrix. Its weights
are the model file's, exactly (the fast kernel's float32 columns widened to float64, and
float64 scales; dense float64 otherwise), summed in float64.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi._version import __version__
from sigmapi.codes import PopulationCode
from sigmapi.errors import ConfigError, ResourceError, UsageError, install_hint
from sigmapi.io import atomic_write_bytes
from sigmapi.kernels import get_backend
from sigmapi.model.som import SigmaPiSOM, load_model
from sigmapi.rules.winners import Scoring

__all__ = ["FORMATS", "INPUTS", "OPSET", "export_onnx", "onnx_model", "score_matrix"]

FORMATS = ("onnx",)
"""The formats :func:`export_onnx` writes (``sigmapi export --format``)."""

INPUTS = ("codes", "positions")
"""What the graph takes: the population codes, or the positions it encodes itself."""

OPSET = 21
"""Default ONNX opset of the graph. Every operator the graph uses is the same from opset 18
(where ``ReduceMax`` took its axes as an input) to the newest; 21 loads in onnxruntime 1.18
and later."""

MIN_OPSET = 18

_MAX_BYTES = 2_000_000_000
"""A single ONNX file (protobuf) holds less than 2 GiB."""


def _onnx() -> Any:
    try:
        import onnx
    except ImportError:
        raise UsageError(
            f"exporting to ONNX needs the onnx package (not installed here); {install_hint('onnx')}"
        ) from None
    return onnx


def score_matrix(model: SigmaPiSOM) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(A, b)`` with ``scores = response @ A + b``: the model's winner rule at its current
    sigma as one affine map ``(n_units, n_units)``, ``(n_units,)``.

    Every rule of :mod:`sigmapi.rules.winners` is affine in the response (the soft rules
    smooth it linearly, ``min_distance`` subtracts the squared norms); a rule that is not
    raises :class:`~sigmapi.errors.ConfigError` (checked on random responses).
    """
    rule = model.winner_rule_
    c = model.config
    k = model.n_units
    sq = model.unit_sqnorms() if rule.needs_norms else None
    at = Scoring(c.geometry, float(model.sigma_), sq)
    b = np.asarray(rule.scores(np.zeros((1, k)), at), dtype=np.float64)[0]
    a = np.asarray(rule.scores(np.eye(k), at), dtype=np.float64) - b[None, :]
    probe = np.random.default_rng(0).standard_normal((4, k))
    want = np.asarray(rule.scores(probe, at), dtype=np.float64)
    got = probe @ a + b
    if not np.allclose(got, want, rtol=1e-9, atol=1e-9 * max(1.0, float(np.abs(want).max()))):
        raise ConfigError(
            f"winner rule {rule.name!r} is not an affine map of the response; ONNX export "
            "supports the rules of sigmapi.rules.WINNER_RULES"
        )
    return a, b


def _columns(model: SigmaPiSOM) -> tuple[NDArray[np.floating], NDArray[np.float64]]:
    """Weights as ``raw`` ``(n_x * n_y, K)`` and ``scale`` ``(K,)``, ``W[k] = scale[k] *
    raw[:, k]``: the kernel's own columns where it keeps them, else dense
    (:meth:`~sigmapi.kernels.base.Kernel.weight_columns`)."""
    _, arrays = model.to_arrays()
    shape = model.weights_.shape
    return get_backend(model.backend).weight_columns((shape[0], shape[1], shape[2]), arrays)


def _truncation(model: SigmaPiSOM) -> float:
    """The share of ``max|x| max|y|`` below which the model's kernel skips a code pair."""
    return get_backend(model.backend).pair_cutoff(model.config.kernel_tol)


def code_meta(code: Any) -> str:
    d = {f.name: getattr(code, f.name) for f in dataclasses.fields(code) if f.init}
    return json.dumps({**d, "shape": list(code.shape)})


def _encoder(code: PopulationCode, pos: str, out: str, init: list[Any]) -> list[Any]:
    """Nodes that turn positions ``pos`` ``(B, d)`` into ``code``'s codes ``out`` ``(B, n)``,
    the arithmetic of :meth:`sigmapi.PopulationCode.encode` (one Gaussian hill per axis,
    their C-order outer product, the height, the L2 normalisation)."""
    from onnx import helper, numpy_helper

    def const(name: str, value: Any) -> str:
        init.append(numpy_helper.from_array(np.asarray(value), name))
        return name

    nodes: list[Any] = []
    code_so_far = ""
    for a, n in enumerate(code.shape):
        p = f"{out}_axis{a}"
        d = f"{p}_diff"
        nodes += [
            helper.make_node(
                "Gather", [pos, const(f"{p}_i", np.array([a], np.int64))], [f"{p}_p"], axis=1
            ),
            helper.make_node(
                "Mul", [f"{p}_p", const(f"{p}_scale", float(code.scale[a]))], [f"{p}_g"]
            ),
            helper.make_node(
                "Sub", [f"{p}_g", const(f"{p}_units", np.arange(n, dtype=float))], [d]
            ),
        ]
        if code.periodic:  # the shorter way round: d - n round(d / n), half to even as NumPy
            size = const(f"{p}_n", float(n))
            nodes += [
                helper.make_node("Div", [d, size], [f"{p}_turns"]),
                helper.make_node("Round", [f"{p}_turns"], [f"{p}_whole"]),
                helper.make_node("Mul", [f"{p}_whole", size], [f"{p}_wrap"]),
                helper.make_node("Sub", [d, f"{p}_wrap"], [f"{p}_wrapped"]),
            ]
            d = f"{p}_wrapped"
        two_w2 = const(f"{p}_two_w2", 2.0 * code.width**2)
        nodes += [
            helper.make_node("Mul", [d, d], [f"{p}_sq"]),
            helper.make_node("Neg", [f"{p}_sq"], [f"{p}_neg"]),
            helper.make_node("Div", [f"{p}_neg", two_w2], [f"{p}_arg"]),
            helper.make_node("Exp", [f"{p}_arg"], [f"{p}_hill"]),
        ]
        if not code_so_far:
            code_so_far = f"{p}_hill"
            continue
        nodes += [
            helper.make_node("Unsqueeze", [code_so_far, "axis2"], [f"{p}_left"]),
            helper.make_node("Unsqueeze", [f"{p}_hill", "axis1"], [f"{p}_right"]),
            helper.make_node("Mul", [f"{p}_left", f"{p}_right"], [f"{p}_outer"]),
            helper.make_node(
                "Reshape", [f"{p}_outer", const(f"{p}_flat", np.array([0, -1]))], [f"{p}_code"]
            ),
        ]
        code_so_far = f"{p}_code"
    height = const(f"{out}_height", float(code.height))
    if not code.normalize:
        return [*nodes, helper.make_node("Mul", [code_so_far, height], [out])]
    return [
        *nodes,
        helper.make_node("Mul", [code_so_far, height], [f"{out}_tall"]),
        helper.make_node("ReduceSumSquare", [f"{out}_tall", "axis1"], [f"{out}_sq"], keepdims=1),
        helper.make_node("Sqrt", [f"{out}_sq"], [f"{out}_norm"]),
        helper.make_node("Div", [f"{out}_tall", f"{out}_norm"], [out]),
    ]


def _dense_response(raw: NDArray[np.floating], pairs: int, init: list[Any]) -> list[Any]:
    """Nodes of ``response`` from ``x``, ``y``, every code pair: the outer products of the
    batch times the weight columns (a model whose kernel skips no pair)."""
    from onnx import TensorProto, helper, numpy_helper

    init.append(numpy_helper.from_array(np.array([0, pairs], np.int64), "flat_shape"))
    nodes = [
        helper.make_node("Unsqueeze", ["x", "axis2"], ["x3"]),
        helper.make_node("Unsqueeze", ["y", "axis1"], ["y3"]),
        helper.make_node("Mul", ["x3", "y3"], ["outer"]),
    ]
    w = "w_raw"
    if raw.dtype != np.float64:
        nodes.append(helper.make_node("Cast", ["w_raw"], ["w64"], to=TensorProto.DOUBLE))
        w = "w64"
    return [
        *nodes,
        helper.make_node("Reshape", ["outer", "flat_shape"], ["pairs"]),
        helper.make_node("MatMul", ["pairs", w], ["sums"]),
        helper.make_node("Mul", ["sums", "w_scale"], ["response"]),
    ]


def _sparse_response(nx: int, ny: int, k: int, tol: float, init: list[Any]) -> list[Any]:
    """The nodes (a ``Scan``) of ``response`` from ``x``, ``y``, one pair at a time, as the fast
    kernel computes it (``kernels/_rows.py``): the thresholds ``thr = tol max|x| max|y|``, the
    retinal units with ``|x_i| max|y| > thr`` and gaze units with ``|y_j| max|x| > thr`` (no
    pair of another unit passes the cut), their outer product, the pairs with
    ``|x_i y_j| > thr`` in the kernel's order (``i`` then ``j``), their weight rows gathered
    and summed in float64 (``w_raw`` float64: the model's float32 columns, exactly, so that no
    row read needs a cast). A pair thus costs the rows of its kept code pairs (about
    1,000-1,300 of the paper-2d map's 50,625), not the whole weight matrix."""
    from onnx import TensorProto, helper, numpy_helper

    def const(name: str, value: Any) -> str:
        init.append(numpy_helper.from_array(np.asarray(value), name))
        return name

    const("tol", np.array(tol, np.float64))
    const("units_x", np.arange(nx, dtype=np.int64))
    const("units_y", np.arange(ny, dtype=np.int64))
    const("n_y", np.array(ny, np.int64))
    const("axis0", np.array([0], np.int64))
    const("flat", np.array([-1], np.int64))
    const("none", np.array(0, np.int64))
    body = [
        helper.make_node("Abs", ["xb"], ["ax"]),
        helper.make_node("Abs", ["yb"], ["ay"]),
        helper.make_node("ReduceMax", ["ax"], ["mx"], keepdims=0),
        helper.make_node("ReduceMax", ["ay"], ["my"], keepdims=0),
        helper.make_node("Mul", ["tol", "mx"], ["thr_x"]),
        helper.make_node("Mul", ["thr_x", "my"], ["thr"]),
        helper.make_node("Mul", ["ax", "my"], ["sx"]),
        helper.make_node("Greater", ["sx", "thr"], ["on_x"]),
        helper.make_node("Mul", ["ay", "mx"], ["sy"]),
        helper.make_node("Greater", ["sy", "thr"], ["on_y"]),
        helper.make_node("Compress", ["xb", "on_x"], ["vx"], axis=0),
        helper.make_node("Compress", ["units_x", "on_x"], ["ix"], axis=0),
        helper.make_node("Compress", ["yb", "on_y"], ["vy"], axis=0),
        helper.make_node("Compress", ["units_y", "on_y"], ["iy"], axis=0),
        helper.make_node("Unsqueeze", ["vx", "axis1"], ["vx2"]),
        helper.make_node("Unsqueeze", ["vy", "axis0"], ["vy2"]),
        helper.make_node("Mul", ["vx2", "vy2"], ["outer2"]),
        helper.make_node("Reshape", ["outer2", "flat"], ["outer"]),
        helper.make_node("Mul", ["ix", "n_y"], ["base"]),
        helper.make_node("Unsqueeze", ["base", "axis1"], ["base2"]),
        helper.make_node("Unsqueeze", ["iy", "axis0"], ["iy2"]),
        helper.make_node("Add", ["base2", "iy2"], ["pair2"]),
        helper.make_node("Reshape", ["pair2", "flat"], ["pair"]),
        helper.make_node("Abs", ["outer"], ["abs_outer"]),
        helper.make_node("Greater", ["abs_outer", "thr"], ["kept"]),
        helper.make_node("Compress", ["outer", "kept"], ["pv"], axis=0),
        helper.make_node("Compress", ["pair", "kept"], ["pi"], axis=0),
        helper.make_node("Gather", ["w_raw", "pi"], ["rows"], axis=0),
        helper.make_node("MatMul", ["pv", "rows"], ["sums"]),
        helper.make_node("Mul", ["sums", "w_scale"], ["hb"]),
    ]
    f64 = TensorProto.DOUBLE
    graph = helper.make_graph(
        body,
        "one_pair",
        [
            helper.make_tensor_value_info("xb", f64, [nx]),
            helper.make_tensor_value_info("yb", f64, [ny]),
        ],
        [helper.make_tensor_value_info("hb", f64, [k])],
    )
    scan = helper.make_node("Scan", ["x", "y"], ["scanned"], body=graph, num_scan_inputs=2)
    const("no_rows", np.zeros((0, k)))
    out = [helper.make_tensor_value_info("rows_out", f64, [None, k])]
    # onnxruntime's Scan refuses an empty batch: no pairs, no rows
    return [
        helper.make_node("Shape", ["x"], ["batch"], start=0, end=1),
        helper.make_node("ReduceMax", ["batch"], ["b"], keepdims=0),
        helper.make_node("Equal", ["b", "none"], ["empty"]),
        helper.make_node(
            "If",
            ["empty"],
            ["response"],
            then_branch=helper.make_graph(
                [helper.make_node("Identity", ["no_rows"], ["rows_out"])], "empty", [], out
            ),
            else_branch=helper.make_graph(
                [scan, helper.make_node("Identity", ["scanned"], ["rows_out"])], "pairs", [], out
            ),
        ),
    ]


def _inputs(graph: Any) -> set[str]:
    """Every value the nodes of ``graph`` (and of their subgraphs) read."""
    names = {n for node in graph.node for n in node.input}
    for node in graph.node:
        for a in node.attribute:
            if a.g.node:
                names |= _inputs(a.g)
    return names


def onnx_model(model: SigmaPiSOM, opset: int = OPSET, inputs: str = "codes") -> Any:
    """The ONNX graph (an ``onnx.ModelProto``) of a fitted model's response and winner.

    ``inputs``: ``"codes"`` (inputs ``x`` and ``y``, the population codes) or
    ``"positions"`` (inputs ``x_position`` ``(B, d_x)`` and ``y_position`` ``(B, d_y)`` in
    [0, 1], encoded in the graph as ``model.x_code.encode`` does; values outside [0, 1] are
    not refused there). See the module's description for the outputs. Raises
    :class:`~sigmapi.errors.UsageError` without the onnx package,
    :class:`~sigmapi.errors.NotFittedError` for a model that has not been trained.
    """
    onnx = _onnx()
    from onnx import TensorProto, helper, numpy_helper

    top = int(onnx.defs.onnx_opset_version())
    opset = _validate.integer(
        "opset", opset, MIN_OPSET, top, fix=f"the default is {OPSET}", error=UsageError
    )
    _validate.choice("inputs", inputs, INPUTS, error=UsageError)
    raw, scale = _columns(model)  # raises NotFittedError before training
    tol = _truncation(model)
    if tol > 0:  # the graph gathers rows of float64 weights: no cast of every row it reads
        raw = raw.astype(np.float64)
    nbytes = raw.nbytes + scale.nbytes
    if nbytes >= _MAX_BYTES:
        raise ResourceError(
            f"the model's weights take {nbytes / 1e9:.2f} GB; one ONNX file holds less than "
            "2 GB; export a smaller map"
        )
    a, b = score_matrix(model)
    k = model.n_units
    nx, ny = int(np.prod(model.x_shape)), int(np.prod(model.y_shape))
    init = [
        numpy_helper.from_array(raw, "w_raw"),
        numpy_helper.from_array(scale.astype(np.float64), "w_scale"),
        numpy_helper.from_array(np.array([1], np.int64), "axis1"),
        numpy_helper.from_array(np.array([2], np.int64), "axis2"),
    ]
    f64 = TensorProto.DOUBLE
    if inputs == "positions":
        nodes = [
            *_encoder(model.x_code, "x_position", "x", init),
            *_encoder(model.y_code, "y_position", "y", init),
        ]
        graph_inputs = [
            helper.make_tensor_value_info("x_position", f64, ["B", len(model.x_shape)]),
            helper.make_tensor_value_info("y_position", f64, ["B", len(model.y_shape)]),
        ]
    else:
        nodes = []
        graph_inputs = [
            helper.make_tensor_value_info("x", f64, ["B", nx]),
            helper.make_tensor_value_info("y", f64, ["B", ny]),
        ]
    if tol > 0:
        nodes += _sparse_response(nx, ny, k, tol, init)
    else:
        nodes += _dense_response(raw, nx * ny, init)
    scores = "response"
    if not np.array_equal(a, np.eye(k)):
        init.append(numpy_helper.from_array(a, "score_matrix"))
        nodes.append(helper.make_node("MatMul", ["response", "score_matrix"], ["smoothed"]))
        scores = "smoothed"
    if np.any(b != 0):
        init.append(numpy_helper.from_array(b, "score_offset"))
        nodes.append(helper.make_node("Add", [scores, "score_offset"], ["scores"]))
        scores = "scores"
    nodes.append(
        helper.make_node("ArgMax", [scores], ["winner"], axis=1, keepdims=0, select_last_index=0)
    )
    used = {n for node in nodes for n in node.input}
    used.update(n for node in nodes for a in node.attribute if a.g.node for n in _inputs(a.g))
    init = [t for t in init if t.name in used]  # e.g. axis2, which only some graphs use
    graph = helper.make_graph(
        nodes,
        "sigmapi_map",
        graph_inputs,
        [
            helper.make_tensor_value_info("response", f64, ["B", k]),
            helper.make_tensor_value_info("winner", TensorProto.INT64, ["B"]),
        ],
        init,
        doc_string=(
            (
                "Sigma-Pi map: inputs x (B, n_x) and y (B, n_y), float64 population codes "
                "(metadata sigmapi.x_code, sigmapi.y_code)"
                if inputs == "codes"
                else "Sigma-Pi map: inputs x_position (B, d_x) and y_position (B, d_y), float64 "
                "positions in [0, 1], encoded as sigmapi.x_code and sigmapi.y_code"
            )
            + "; outputs response (B, n_units) and winner (B,), the flat index of the winning "
            "unit (map_shape in C order)."
        ),
    )
    proto = helper.make_model(
        graph,
        opset_imports=[helper.make_opsetid("", opset)],
        producer_name="sigmapi",
        producer_version=__version__,
    )
    proto.ir_version = min(proto.ir_version, 10)  # what opsets 18-23 need; older runtimes load it
    rule = model.winner_rule_
    meta = {
        "sigmapi.map_shape": json.dumps(list(model.map_shape)),
        "sigmapi.map_periodic": json.dumps(bool(model.config.map_periodic)),
        "sigmapi.x_code": code_meta(model.x_code),
        "sigmapi.y_code": code_meta(model.y_code),
        "sigmapi.winner_rule": rule.name,
        "sigmapi.sigma": repr(float(model.sigma_)),
        "sigmapi.kernel_tol": repr(tol),
        "sigmapi.iterations": str(model.t_),
        "sigmapi.inputs": inputs,
    }
    helper.set_model_props(proto, meta)
    onnx.checker.check_model(proto)
    return proto


def export_onnx(
    model: SigmaPiSOM | str | Path,
    out: str | Path,
    *,
    opset: int = OPSET,
    inputs: str = "codes",
    force: bool = False,
) -> Path:
    """Write the ONNX graph of ``model`` (a fitted model or a model file) to ``out``,
    atomically; returns the path.

    Refuses an existing ``out`` unless ``force`` (:class:`~sigmapi.errors.UsageError`); a
    model file is read as :func:`sigmapi.load` reads it (a damaged or hostile file raises
    :class:`~sigmapi.errors.ModelFileError`; nothing is unpickled).
    """
    target = Path(out)
    if target.exists() and not force:
        raise UsageError(f"out {str(target)!r} exists; pass force=True (--force) to overwrite it")
    _onnx()  # before reading a large model
    som = model if isinstance(model, SigmaPiSOM) else load_model(model)
    proto = onnx_model(som, opset, inputs)
    return atomic_write_bytes(target, proto.SerializeToString())
