"""``sigmapi export``: the ONNX graph of a map gives the model's own winners and responses."""

from __future__ import annotations

import numpy as np
import pytest

import sigmapi
from sigmapi import SigmaPiSOM
from sigmapi.cli import main
from sigmapi.errors import ModelFileError, UsageError

ort = pytest.importorskip("onnxruntime")
onnx = pytest.importorskip("onnx")

from sigmapi.export import export_onnx, onnx_model  # noqa: E402

N_PAIRS = 10_000


def _trained(tmp_path_factory, name, **kw) -> str:
    som = SigmaPiSOM(**kw).fit()
    return str(som.save(tmp_path_factory.mktemp(name) / "m.npz"))


@pytest.fixture(scope="module")
def map_1d(tmp_path_factory):
    """A 1-D map of the paper's procedure (ordered start, soft winner border-normalised,
    refinement) at the paper's sizes, on the fast kernel with its truncation."""
    cfg = sigmapi.load_preset("paper-1d")
    return _trained(tmp_path_factory, "m1", config=cfg, iterations=4000, refine_pairs=4000, seed=3)


@pytest.fixture(scope="module")
def map_2d(tmp_path_factory):
    """A small 2-D map of paper-2d's procedure (min-distance winner, kernel_tol 1e-4)."""
    cfg = sigmapi.load_preset("paper-2d")
    return _trained(tmp_path_factory, "m2", config=cfg, map_shape=(6, 6), x_shape=(7, 7),
                    y_shape=(7, 7), iterations=3000, refine_pairs=3000, seed=3)  # fmt: skip


@pytest.fixture(scope="module")
def torus(tmp_path_factory):
    """A periodic 2-D map with the soft winner mid-run (sigma still wide: smoothing wraps)."""
    cfg = sigmapi.load_preset("angles-2d")
    return _trained(tmp_path_factory, "m3", config=cfg, map_shape=(5, 6), x_shape=(6, 6),
                    y_shape=(6, 6), iterations=1500, seed=3, refine_rounds=0,
                    sigma=((0.0, 3.0), (1.0, 2.0)))  # fmt: skip


def _round_trip(model_file, out, seed=0, n=N_PAIRS):
    m = sigmapi.load(model_file)
    rng = np.random.default_rng(seed)
    d = len(m.x_shape)
    x = m.x_code.encode(rng.random((n, d)))
    y = m.y_code.encode(rng.random((n, d)))
    session = ort.InferenceSession(str(out), providers=["CPUExecutionProvider"])
    response, winner = session.run(["response", "winner"], {"x": x, "y": y})
    return m, x, y, response, winner


@pytest.mark.parametrize("which", ["map_1d", "map_2d", "torus"])
def test_onnx_gives_the_models_winners_on_10000_random_pairs(which, request, tmp_path):
    model_file = request.getfixturevalue(which)
    out = tmp_path / "map.onnx"
    assert main(["export", model_file, "--format", "onnx", "--out", str(out)]) == 0
    m, x, y, response, winner = _round_trip(model_file, out)
    assert winner.shape == (N_PAIRS,) and winner.dtype == np.int64
    np.testing.assert_array_equal(winner, m.winner(x, y))
    want = m.respond(x, y)
    assert response.shape == want.shape == (N_PAIRS, m.n_units)
    np.testing.assert_allclose(response, want, rtol=0, atol=1e-12 * np.abs(want).max())
    # the winners are not trivial: the random pairs reach many units
    assert len(np.unique(winner)) > m.n_units // 2


def test_the_graph_carries_the_codes_and_the_rule(map_2d):
    m = sigmapi.load(map_2d)
    proto = onnx_model(m)
    meta = {p.key: p.value for p in proto.metadata_props}
    assert meta["sigmapi.winner_rule"] == m.winner_rule_.name
    assert '"width": 1.0' in meta["sigmapi.x_code"] and '"shape": [7, 7]' in meta["sigmapi.x_code"]
    assert [i.name for i in proto.graph.input] == ["x", "y"]
    assert [o.name for o in proto.graph.output] == ["response", "winner"]
    assert proto.opset_import[0].version == 21


def test_export_refuses_bad_input_in_one_line(map_1d, tmp_path, capsys):
    out = tmp_path / "a.onnx"
    out.write_bytes(b"keep me")
    cases = [
        (["export", map_1d, "--format", "tflite", "--out", str(tmp_path / "b")], "--format"),
        (["export", str(tmp_path / "missing.npz"), "--format", "onnx", "--out",
          str(tmp_path / "c.onnx")], "does not exist"),
        (["export", map_1d, "--format", "onnx", "--out", str(out)], "--force"),
        (["export", map_1d, "--format", "onnx", "--out", str(tmp_path / "d.onnx"),
          "--opset", "7"], "opset"),
    ]  # fmt: skip
    for argv, words in cases:
        with pytest.raises(SystemExit) if "tflite" in argv else _no_raise():
            code = main(argv)
            assert code == 2
        err = capsys.readouterr().err
        assert words in err and len(err.strip().splitlines()) == 1, err
        assert "Traceback" not in err
    assert out.read_bytes() == b"keep me"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.onnx"]


class _no_raise:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_hostile_model_files_are_refused_and_nothing_is_written(tmp_path, capsys):
    evil = tmp_path / "evil.npz"
    np.savez(evil, header=np.array([{"__reduce__": "os.system"}], dtype=object),
             weights=np.zeros((3, 4, 4)))  # fmt: skip
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"PK\x03\x04" + bytes(range(256)) * 4)
    for bad in (evil, junk):
        out = tmp_path / f"{bad.stem}.onnx"
        with pytest.raises(ModelFileError):
            export_onnx(bad, out)
        assert main(["export", str(bad), "--format", "onnx", "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
        assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["evil.npz", "junk.npz"]


def test_an_unfitted_model_and_an_existing_file_are_refused(map_1d, tmp_path):
    with pytest.raises(sigmapi.NotFittedError):
        export_onnx(SigmaPiSOM(map_shape=(3,), x_shape=(3,), y_shape=(3,)), tmp_path / "u.onnx")
    out = tmp_path / "m.onnx"
    export_onnx(map_1d, out)
    with pytest.raises(UsageError, match="exists"):
        export_onnx(map_1d, out)
    before = out.stat().st_size
    export_onnx(map_1d, out, force=True)
    assert out.stat().st_size == before


def test_a_reference_backend_model_exports_its_dense_weights_exactly(small_1d, tmp_path):
    som = SigmaPiSOM(small_1d).fit()  # the reference kernel: dense float64, no skipped pairs
    out = export_onnx(som, tmp_path / "r.onnx")
    proto = onnx.load(str(out))
    meta = {p.key: p.value for p in proto.metadata_props}
    assert som.backend == "reference" and float(meta["sigmapi.kernel_tol"]) == 0.0
    rng = np.random.default_rng(4)
    x, y = som.x_code.encode(rng.random((N_PAIRS, 1))), som.y_code.encode(rng.random((N_PAIRS, 1)))
    session = ort.InferenceSession(str(out), providers=["CPUExecutionProvider"])
    response, winner = session.run(["response", "winner"], {"x": x, "y": y})
    np.testing.assert_array_equal(winner, som.winner(x, y))
    np.testing.assert_allclose(response, som.respond(x, y), rtol=0, atol=1e-12)


@pytest.mark.parametrize("which", ["map_1d", "map_2d", "torus"])
def test_a_graph_that_takes_positions_encodes_them_as_the_model_does(which, request, tmp_path):
    model_file = request.getfixturevalue(which)
    out = tmp_path / "p.onnx"
    argv = ["export", model_file, "--format", "onnx", "--inputs", "positions", "--out", str(out)]
    assert main(argv) == 0
    m = sigmapi.load(model_file)
    rng = np.random.default_rng(1)
    px, py = rng.random((N_PAIRS, len(m.x_shape))), rng.random((N_PAIRS, len(m.y_shape)))
    px[:3], py[:3] = 0.0, 1.0  # the ends of the axes (the same place on a ring)
    session = ort.InferenceSession(str(out), providers=["CPUExecutionProvider"])
    assert [i.name for i in session.get_inputs()] == ["x_position", "y_position"]
    response, winner = session.run(["response", "winner"], {"x_position": px, "y_position": py})
    x, y = m.x_code.encode(px), m.y_code.encode(py)
    np.testing.assert_array_equal(winner, m.winner(x, y))
    want = m.respond(x, y)
    np.testing.assert_allclose(response, want, rtol=0, atol=1e-12 * np.abs(want).max())


def test_a_fast_model_s_graph_reads_only_the_kept_pairs_rows(map_2d):
    """The graph of a fast-kernel model gathers the weight rows of each pair's kept code
    pairs (a Scan over the batch) instead of multiplying all n_x n_y pairs; zero codes and an
    empty batch answer as ``respond`` and ``winner`` do."""
    m = sigmapi.load(map_2d)
    proto = onnx_model(m)
    top = [n.op_type for n in proto.graph.node]
    assert "If" in top and "MatMul" not in top[: top.index("If")]
    assert {i.name for i in proto.graph.initializer} >= {"w_raw", "tol"}
    assert "flat_shape" not in {i.name for i in proto.graph.initializer}
    session = ort.InferenceSession(proto.SerializeToString(), providers=["CPUExecutionProvider"])
    rng = np.random.default_rng(7)
    x, y = m.x_code.encode(rng.random((4, 2))), m.y_code.encode(rng.random((4, 2)))
    x[1], y[2] = 0.0, 0.0
    response, winner = session.run(["response", "winner"], {"x": x, "y": y})
    np.testing.assert_array_equal(winner, m.winner(x, y))
    np.testing.assert_allclose(response, m.respond(x, y), rtol=0, atol=1e-12)
    assert not response[1].any() and not response[2].any()
    response, winner = session.run(["response", "winner"], {"x": x[:0], "y": y[:0]})
    assert response.shape == (0, m.n_units) and winner.shape == (0,)
