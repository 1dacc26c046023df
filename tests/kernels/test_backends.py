"""The backend registry and its contract: a third backend, defined here, plugs in with no edit
outside this file (trains, saves, loads, also onto another backend, and continues); entry
points are discovered lazily; a new winner rule is one object."""

from __future__ import annotations

import zipfile
from dataclasses import dataclass

import numpy as np
import pytest
from numpy.typing import NDArray

import sigmapi
from sigmapi import ConfigError, ModelFileError, SigmaPiSOM, SOMConfig, kernels
from sigmapi.kernels import BACKENDS, get_backend, reference, register_backend
from sigmapi.kernels.base import CONTRACT, KernelBase
from sigmapi.rules import WINNER_RULES, Scoring, WinnerRule
from sigmapi.rules.geometry import MapGeometry
from sigmapi.rules.neighbourhood import neighbourhood

CFG = SOMConfig(map_shape=(3, 2), x_shape=(4,), y_shape=(5,), iterations=900, seed=5,
                sigma=((0.0, 2.0), (0.6, 1e-5)), ordering="none")  # fmt: skip


# ---------------------------------------------------------------------------- a toy backend


@dataclass
class ToyState:
    """The toy backend's state: dense float64 weights in a dataclass."""

    w: NDArray[np.float64]

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(self.w.shape)


class ToyKernel(KernelBase[ToyState]):
    """A third backend: the reference arithmetic on its own state and file array; the rest is
    the base's generic defaults."""

    NAME = "toy"

    def prepare(self, weights, tol=0.0):
        return ToyState(np.array(weights, dtype=np.float64))

    def export(self, state):
        return state.w

    def activation(self, state, x, y):
        return reference.activation(state.w, x, y)

    def train_block(self, state, x0, y0, x1, y1, sigmas, eps, **kw):
        return reference.KERNEL.train_block(state.w, x0, y0, x1, y1, sigmas, eps, **kw)

    def file_arrays(self, state):
        return {"state_toy": state.w.copy()}

    def from_file_arrays(self, shape, arrays, tol=0.0):
        if set(arrays) != {"state_toy"} or arrays["state_toy"].shape != tuple(shape):
            raise ValueError(f"the toy backend stores state_toy {shape}, got {sorted(arrays)}")
        return ToyState(np.array(arrays["state_toy"], dtype=np.float64))

    def file_weights(self, shape, arrays):
        return self.from_file_arrays(shape, arrays).w


@pytest.fixture
def registry(monkeypatch):
    """A registry of this test's own: what a test registers leaves no trace in others."""
    monkeypatch.setattr(kernels, "REGISTRY", dict(kernels.REGISTRY))
    return kernels.REGISTRY


@pytest.fixture
def toy(registry):
    register_backend("toy", ToyKernel())
    return "toy"


def test_a_registered_backend_trains_like_the_arithmetic_it_wraps(toy):
    assert "toy" in BACKENDS
    model = SigmaPiSOM(CFG, backend=toy).fit()
    ref = SigmaPiSOM(CFG, backend="reference").fit()
    assert model.backend == "toy" and isinstance(model._run.state, ToyState)
    np.testing.assert_array_equal(model.weights_, ref.weights_)
    b = model.sampler.sample(50, np.random.default_rng(1))
    np.testing.assert_array_equal(model.winner(b.x0, b.y0), ref.winner(b.x0, b.y0))
    np.testing.assert_array_equal(model.respond(b.x0, b.y0), ref.respond(b.x0, b.y0))
    assert model.cost(b) == ref.cost(b)
    assert model.memory_estimate() == ref.memory_estimate()


def test_a_registered_backend_saves_loads_and_continues(toy, tmp_path):
    model = SigmaPiSOM(CFG, backend=toy).fit(iterations=600)
    path = model.save(tmp_path / "toy.npz")
    assert sorted(zipfile.ZipFile(path).namelist()) == ["header.npy", "state_toy.npy"]
    back = sigmapi.load(path)
    assert back.backend == "toy" and back.t_ == 600
    np.testing.assert_array_equal(back.partial_fit().weights_, model.partial_fit().weights_)
    # onto every other backend: the same weights, and the run goes on there
    for other in BACKENDS:
        moved = sigmapi.load(path, backend=other)
        assert moved.backend == other
        np.testing.assert_allclose(moved.weights_, SigmaPiSOM.load(path).weights_, rtol=1e-7)
        assert moved.partial_fit(iterations=100).t_ == 700
    # and a file of another backend loads onto the toy one
    ref_path = SigmaPiSOM(CFG, backend="reference").fit(iterations=300).save(tmp_path / "r.npz")
    onto = sigmapi.load(ref_path, backend=toy)
    np.testing.assert_array_equal(onto.weights_, sigmapi.load(ref_path).weights_)


def test_a_file_of_a_backend_not_installed_here(toy, tmp_path):
    path = SigmaPiSOM(CFG, backend=toy).fit(iterations=100).save(tmp_path / "toy.npz")
    del kernels.REGISTRY["toy"]
    with pytest.raises(ModelFileError, match="backend 'toy', which is not available here"):
        sigmapi.load(path, backend="reference")
    with pytest.raises(ModelFileError, match="backend must be one of"):
        sigmapi.load(path)  # its config names the toy backend


def test_register_backend_checks_the_name_and_the_contract(registry):
    with pytest.raises(ConfigError, match="NAME 'toy'"):
        register_backend("other", ToyKernel())
    with pytest.raises(ConfigError, match="lower-case identifier"):
        register_backend("auto", ToyKernel())
    with pytest.raises(ConfigError, match="registered already"):
        register_backend("reference", ToyKernel())

    class Half:
        NAME = "half"
        prepare = ToyKernel.prepare

    with pytest.raises(ConfigError, match=r"lacks \[.*'train_block'\]"):
        register_backend("half", Half())
    assert "half" not in BACKENDS


# ---------------------------------------------------------------------------- every backend


@pytest.mark.parametrize("backend", [*BACKENDS, "toy"])
def test_every_backend_keeps_the_contract(registry, backend):
    """The contract's parts agree with one another on every backend: file arrays round-trip,
    winners are the argmax of the scores, the neighbourhood is the rules' one."""
    if backend == "toy":
        register_backend("toy", ToyKernel())
    kernel = get_backend(backend)
    assert all(hasattr(kernel, n) for n in CONTRACT) and kernel.NAME == backend
    w = SigmaPiSOM(CFG).initial_weights()
    state = kernel.prepare(w, 0.0)
    arrays = kernel.file_arrays(state)
    assert all(k == "weights" or k.startswith("state_") for k in arrays)
    back = kernel.from_file_arrays(w.shape, arrays, 0.0)
    np.testing.assert_array_equal(kernel.export(back), kernel.export(state))
    np.testing.assert_array_equal(kernel.file_weights(w.shape, arrays), kernel.export(state))
    assert kernel.max_abs(state) == float(np.abs(kernel.export(state)).max())
    assert kernel.memory_bytes(w.shape, 0.0) >= w.size * 4
    b = SigmaPiSOM(CFG).sampler.sample(20, np.random.default_rng(0))
    h = kernel.activation(state, b.x0, b.y0)
    for name, rule in WINNER_RULES.items():
        assert kernel.supports(rule) and kernel.supports(name)
        s = kernel.scores(state, h, CFG.geometry, rule, 0.8)
        win = kernel.winners(state, h, CFG.geometry, name, 0.8)
        np.testing.assert_array_equal(win, np.argmax(s, axis=1))
        np.testing.assert_array_equal(
            kernel.winners_of(state, b.x0, b.y0, CFG.geometry, rule, 0.8), win
        )
    k = np.array([0, 5])
    np.testing.assert_array_equal(
        kernel.neighbourhood(k, MapGeometry(CFG.map_shape, True), 1.2),
        neighbourhood(k, MapGeometry(CFG.map_shape, True), 1.2),
    )


# ---------------------------------------------------------------------------- entry points


class _EntryPoint:
    """What ``importlib.metadata.entry_points`` yields, as far as sigmapi reads it."""

    def __init__(self, name, load):
        self.name, self.value, self.loads, self._load = name, f"plugin:{name}", 0, load

    def load(self):
        self.loads += 1
        return self._load()


def _plugin(name):
    kernel = ToyKernel()
    kernel.NAME = name
    return kernel


def test_entry_point_backends_are_found_and_loaded_on_first_use(registry, monkeypatch):
    plug = _EntryPoint("plug", lambda: _plugin("plug"))
    broken = _EntryPoint("broken", lambda: __import__("sigmapi_no_such_module"))
    taken = _EntryPoint("fast", lambda: _plugin("fast"))
    groups = []

    def entry_points(group):
        groups.append(group)
        return [plug, broken, taken]

    monkeypatch.setattr(kernels, "entry_points", entry_points)
    monkeypatch.setattr(kernels, "_discovered", False)
    with pytest.warns(UserWarning, match="entry point 'fast'.*ignored"):
        names = list(BACKENDS)
    assert groups == ["sigmapi.kernels"] and names[-2:] == ["plug", "broken"]
    assert plug.loads == 0  # named, not imported
    cfg = CFG.replace(backend="plug")
    assert plug.loads == 0
    model = SigmaPiSOM(cfg).fit(iterations=200)
    assert plug.loads == 1 and model.backend == "plug"
    SigmaPiSOM(cfg)
    assert plug.loads == 1 and list(BACKENDS) == names and groups == ["sigmapi.kernels"]
    with pytest.raises(ConfigError, match="backend 'broken' needs the package of entry point"):
        get_backend("broken")
    assert taken.loads == 0 and get_backend("fast") is not None


def test_without_numba_auto_is_the_reference_and_fast_files_still_load(registry, tmp_path):
    path = SigmaPiSOM(CFG, backend="fast").fit(iterations=300).save(tmp_path / "f.npz")
    want = sigmapi.load(path).weights_

    def no_numba():
        raise ImportError("No module named 'numba'")

    registry["fast"] = kernels._Lazy(no_numba, "numba")
    assert get_backend("auto") is reference.KERNEL
    with pytest.raises(ConfigError, match="backend 'fast' needs numba, which does not import"):
        get_backend("fast")
    moved = sigmapi.load(path, backend="reference")  # the fast layout reads without numba
    np.testing.assert_array_equal(moved.weights_, want)


# ---------------------------------------------------------------------------- a new rule


class Lowest(WinnerRule):
    """A rule of this test's own: the unit of the lowest activation."""

    name = "lowest"

    def scores(self, h, at: Scoring):
        return -np.asarray(h)


def test_a_new_winner_rule_is_one_object(monkeypatch):
    monkeypatch.setitem(WINNER_RULES, "lowest", Lowest())
    cfg = CFG.replace(winner_rule="lowest")
    ref = SigmaPiSOM(cfg, backend="reference").fit(iterations=200)  # the reference runs it at once
    assert ref.winner_rule_ is WINNER_RULES["lowest"]
    b = ref.sampler.sample(30, np.random.default_rng(0))
    np.testing.assert_array_equal(ref.winner(b.x0, b.y0), ref.respond(b.x0, b.y0).argmin(1))
    fast = get_backend("fast")
    assert not fast.supports("lowest") and fast.supports("soft")
    with pytest.raises(ConfigError, match="'lowest' has no compiled form in the fast kernel"):
        SigmaPiSOM(cfg, backend="fast").fit(iterations=10)
    with pytest.raises(ConfigError, match="winner_rule must be one of"):
        SOMConfig(winner_rule="farthest")
