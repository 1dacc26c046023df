"""``sigmapi export --format nir``: the map as a NIR graph of spiking neurons that reads back
exactly and, simulated, picks the model's winners."""

from __future__ import annotations

import numpy as np
import pytest

import sigmapi
from sigmapi import SigmaPiSOM
from sigmapi.cli import main

nir = pytest.importorskip("nir")

from sigmapi.neurons.nir_graph import nir_graph, winners  # noqa: E402

CHAIN = ["input", "conjunction", "conjunction_if", "map", "map_lif", "output"]


@pytest.fixture(scope="module")
def map_1d():
    """A paper-1d map on a seed the graph's settings were not chosen on (they were on 0-1)."""
    return SigmaPiSOM(sigmapi.load_preset("paper-1d"), seed=7).fit()


@pytest.fixture(scope="module")
def model_file(map_1d, tmp_path_factory):
    return str(map_1d.save(tmp_path_factory.mktemp("nir") / "m.npz"))


def _fresh_pairs(m, n, seed):
    rng = np.random.default_rng(seed)
    d = len(m.x_shape)
    return m.x_code.encode(rng.random((n, d))), m.y_code.encode(rng.random((n, d)))


def test_the_nir_file_reads_back_exactly(model_file, map_1d, tmp_path):
    out = tmp_path / "map.nir"
    assert main(["export", model_file, "--format", "nir", "--out", str(out)]) == 0
    back = nir.read(str(out))
    want = nir_graph(map_1d)
    assert sorted(back.nodes) == sorted(CHAIN) and sorted(back.edges) == sorted(want.edges)
    kinds = {k: type(v).__name__ for k, v in back.nodes.items()}
    assert kinds == {"input": "Input", "conjunction": "Affine", "conjunction_if": "IF",
                     "map": "Affine", "map_lif": "LIF", "output": "Output"}  # fmt: skip
    nx, ny = map_1d.x_code.size, map_1d.y_code.size  # a conjunction per pair, a relay per unit
    assert back.nodes["conjunction_if"].v_threshold.shape == (nx * ny + nx + ny,)
    for name, node in want.nodes.items():
        for field, value in node.to_dict().items():
            if isinstance(value, np.ndarray):
                got = back.nodes[name].to_dict()[field]
                assert got.dtype == value.dtype, (name, field)
                np.testing.assert_array_equal(got, value, err_msg=f"{name}.{field}")
    assert back.metadata["steps"] == want.metadata["steps"]
    assert back.metadata["x_code"] == want.metadata["x_code"]


def _simulate(graph, inputs):
    """The NIR primitives by their definitions (NIR's docs: Affine ``W x + b``; IF
    ``dv/dt = R I``; LIF ``tau dv/dt = (v_leak - v) + R I``; spike when ``v > v_threshold``,
    then ``v = v_reset``), forward Euler at the graph's ``dt``, written here from the spec,
    not from the exporter; returns the output layer's spike counts and each output neuron's
    last spike's step (-1: none)."""
    dt, steps = float(graph.metadata["dt"]), int(graph.metadata["steps"])
    order, layer = ["conjunction", "conjunction_if", "map", "map_lif"], {}
    state = {name: None for name in order}
    counts = last = None
    for step in range(steps):
        signal = inputs
        for name in order:
            node = graph.nodes[name]
            if isinstance(node, nir.Affine):
                signal = signal @ node.weight.T.astype(np.float64) + node.bias
                continue
            v = state[name] if state[name] is not None else np.zeros_like(signal)
            if isinstance(node, nir.IF):
                v = v + dt * node.r * signal
            else:
                v = v + dt / node.tau * ((node.v_leak - v) + node.r * signal)
            spikes = v > node.v_threshold
            state[name] = np.where(spikes, node.v_reset, v)
            signal = spikes.astype(np.float64)
            layer[name] = signal
        counts = signal if counts is None else counts + signal
        last = np.where(signal > 0, step, -1 if last is None else last)
    return counts, last


def _winners(counts, last):
    """The graph's readout (its metadata's ``readout``), written here from that text: the
    most spikes, then the earliest last spike, then the lowest index."""
    firsts = [
        np.lexsort((np.arange(len(c)), np.where(c > 0, t, 0), -c))[0]
        for c, t in zip(counts, last, strict=True)
    ]
    return np.array(firsts)


def test_the_readout_counts_spikes_then_takes_the_earliest_last_spike():
    counts = np.array([[3, 5, 5, 1], [2, 2, 0, 2], [0, 0, 0, 0], [4, 4, 4, 4]])
    last = np.array([[90, 80, 70, 10], [50, 30, -1, 30], [-1, -1, -1, -1], [9, 9, 9, 9]])
    want = [2, 1, 0, 0]  # earliest last spike among the most; then the lowest index
    np.testing.assert_array_equal(winners(counts, last), want)
    np.testing.assert_array_equal(_winners(counts, last), want)


def test_the_graph_simulated_picks_the_models_winners(map_1d):
    """An independent forward-Euler simulation of the primitives: winners equal to the
    model's on >= 95 % of 400 fresh pairs (paper-1d seed 7: 98.3 %)."""
    graph = nir_graph(map_1d)
    x, y = _fresh_pairs(map_1d, 400, seed=2024)
    counts, last = _simulate(graph, np.concatenate([x, y], axis=1))
    got = _winners(counts, last)
    np.testing.assert_array_equal(got, winners(counts, last))
    agree = np.mean(got == map_1d.winner(x, y))
    print(f"reference simulation: {agree:.3f} of {len(x)} fresh pairs")
    assert agree >= 0.95, agree
    assert counts.max(axis=1).min() >= 1  # every winner fired: no pair read by index alone


def test_nir_refuses_the_onnx_options_in_one_line(model_file, tmp_path, capsys):
    for extra in (["--inputs", "positions"], ["--opset", "19"]):
        out = tmp_path / "a.nir"
        argv = ["export", model_file, "--format", "nir", "--out", str(out), *extra]
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert extra[0] in err and "onnx" in err and len(err.strip().splitlines()) == 1, err
        assert not out.exists()


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:nirtorch.load is being deprecated:DeprecationWarning")
def test_norse_simulates_the_file_with_the_models_winners(model_file, map_1d, tmp_path):
    """Norse (an independent NIR reader; needs torch: ~30 s and ~800 MB to install, CPU
    build) simulates the file: winners equal to the model's on >= 95 % of 500 fresh pairs
    (paper-1d seed 7: 97.8 %; ~40 s, 5.5 min on the loaded shared machine)."""
    torch = pytest.importorskip("torch")
    norse = pytest.importorskip("norse.torch")
    out = tmp_path / "map.nir"
    assert main(["export", model_file, "--format", "nir", "--out", str(out)]) == 0
    graph = nir.read(str(out))
    net = norse.from_nir(graph, dt=float(graph.metadata["dt"]))
    x, y = _fresh_pairs(map_1d, 500, seed=77)
    inputs = torch.tensor(np.concatenate([x, y], axis=1), dtype=torch.float32)
    counts, state = torch.zeros(500, map_1d.n_units), None
    last = torch.full_like(counts, -1.0)
    with torch.no_grad():
        for step in range(int(graph.metadata["steps"])):
            spikes, state = net(inputs, state)
            counts += spikes
            last[spikes > 0] = step
    agree = np.mean(_winners(counts.numpy(), last.numpy()) == map_1d.winner(x, y))
    print(f"norse: {agree:.3f} of 500 fresh pairs")
    assert agree >= 0.95, agree
