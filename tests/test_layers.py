"""The import graph of ``src/sigmapi``: no module imports the CLI, no loops, only downward.

Every ``import`` and ``from ... import`` counts, wherever it stands (module level, inside a
function, under ``TYPE_CHECKING``), so the rule holds for readers and tools, not only at run
time. The package's ``__init__`` (the public names) is no layer: nothing imports it.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGE = SRC / "sigmapi"

LAYERS: tuple[tuple[str, ...], ...] = (
    ("cli",),
    ("experiments",),
    ("envs", "agents", "baselines", "neurons", "viz"),
    ("analysis", "checkpoints", "executor", "export", "nwb"),
    ("metrics",),
    ("model", "_outputs"),
    ("io", "config", "kernels", "tasks", "rules"),
    ("codes", "schedules"),
    ("errors", "_validate", "_memory", "_lock", "_startup", "progress", "_version"),
)
"""Top to bottom: a module may import modules of its own layer (without a loop) or below."""


def _name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


MODULES = {_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _resolve(name: str) -> str | None:
    """The sigmapi module that ``name`` refers to (a module, or the module defining it)."""
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name or None


def _imports(module: str) -> set[str]:
    path = MODULES[module]
    tree = ast.parse(path.read_text("utf-8"), str(path))
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(package.split(".")[: len(package.split(".")) - node.level + 1])
                base = f"{base}.{node.module}" if node.module else base
            names = [f"{base}.{a.name}" for a in node.names]
        else:
            continue
        for n in names:
            if n == "sigmapi" or n.startswith("sigmapi."):
                target = _resolve(n)
                if target is not None and target != module:
                    found.add(target)
    return found


GRAPH = {m: _imports(m) for m in MODULES}


def _layer(module: str) -> int:
    top = module.split(".")[1]
    for i, names in enumerate(LAYERS):
        if top in names:
            return i
    raise AssertionError(f"module {module} is in no layer; add it to LAYERS")


def test_every_module_has_a_layer():
    for m in MODULES:
        if m != "sigmapi":
            _layer(m)


def test_nothing_outside_the_cli_imports_the_cli():
    for m, targets in GRAPH.items():
        if not m.startswith("sigmapi.cli"):
            bad = sorted(t for t in targets if t.startswith("sigmapi.cli"))
            assert not bad, f"{m} imports {bad}"


def test_nothing_imports_the_package_facade():
    for m, targets in GRAPH.items():
        assert "sigmapi" not in targets, f"{m} imports the package namespace; import the module"


def test_imports_only_go_down_the_layers():
    bad = [
        f"{m} ({LAYERS[_layer(m)]}) imports {t} ({LAYERS[_layer(t)]})"
        for m, targets in GRAPH.items()
        if m != "sigmapi"
        for t in sorted(targets - {"sigmapi"})
        if _layer(t) < _layer(m)
    ]
    assert not bad, "upward imports:\n" + "\n".join(bad)


def test_the_import_graph_has_no_loop():
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(m: str) -> None:
        state[m] = 1
        path.append(m)
        for t in sorted(GRAPH[m]):
            if state.get(t) == 1:
                loop = [*path[path.index(t) :], t]
                pytest.fail("import loop: " + " -> ".join(loop))
            if t not in state:
                visit(t)
        path.pop()
        state[m] = 2

    for m in sorted(GRAPH):
        if m not in state:
            visit(m)


KIT = "sigmapi.experiments.kit"
SHARED = ("sigmapi.experiments", "sigmapi.experiments.base", KIT)
"""What every experiment package may import from ``experiments/``: the registry and the kit."""

BORROWS = {
    ("reward", "reach"),
    ("robot", "reach"),
    ("icub", "chain"),
}
"""An experiment package that uses another's parts (the report and the reach experiment share
none: the report imports its sections by ``"module:function"``, written against the kit's
``Section``): the reward experiment's world and map are the reach
experiment's config parts; the robot is the reach experiment in the robot's world (its run,
its per-seed job); the iCub's head map reads its eye map through the chain
experiment's code of map A (``head_code``)."""


def _package(module: str) -> str | None:
    """The experiment package of ``module`` (``reach`` for ``sigmapi.experiments.reach.run``)."""
    parts = module.split(".")
    if len(parts) < 3 or parts[1] != "experiments" or parts[2] in ("base", "kit"):
        return None
    return parts[2]


def test_the_kit_imports_no_experiment_and_experiments_only_the_kit_and_their_own():
    bad = []
    for m, targets in GRAPH.items():
        for t in targets:
            if not t.startswith("sigmapi.experiments.") or t.startswith(SHARED[1:]):
                continue
            if m.startswith(KIT):
                bad.append(f"{m} (the kit) imports the experiment module {t}")
                continue
            mine, theirs = _package(m), _package(t)
            if mine is not None and theirs not in (mine, None) and (mine, theirs) not in BORROWS:
                bad.append(f"{m} imports {t}, another experiment's module")
    assert not bad, "\n".join(bad)


FACADE = "sigmapi.model.som"
MODES = ("sigmapi.model._train", "sigmapi.model._refine", "sigmapi.model._stream")
"""The estimator's room: its public face (``som``) over one run state (``model/_run.py``) and
the training modes, functions on it."""


def test_the_estimators_parts_sit_below_its_face():
    """No module of ``model/`` imports the face, and only the face and the modes themselves
    call a training mode: the run state and the modes never see the estimator."""
    bad = []
    for m, targets in GRAPH.items():
        if m.startswith("sigmapi.model") and FACADE in targets:
            bad.append(f"{m} imports the estimator's face {FACADE}")
        for t in sorted(targets & set(MODES)):
            if m != FACADE and m not in MODES:
                bad.append(f"{m} imports the training mode {t}; call it through SigmaPiSOM")
    assert not bad, "\n".join(bad)


def _written(module: str) -> list[ast.Attribute]:
    """The attributes ``module`` assigns to (``a.b = ...``, ``a.b += ...``, in tuples too)."""
    tree = ast.parse(MODULES[module].read_text("utf-8"))
    found = []
    for node in ast.walk(tree):
        targets = (
            node.targets
            if isinstance(node, ast.Assign)
            else [node.target]
            if isinstance(node, ast.AugAssign | ast.AnnAssign)
            else []
        )
        for t in targets:
            for leaf in ast.walk(t):
                if isinstance(leaf, ast.Attribute) and isinstance(leaf.ctx, ast.Store):
                    found.append(leaf)
    return found


def test_only_the_run_state_and_the_training_modes_write_the_run():
    """The estimator's private state is its one run state: no part of ``model/`` writes a
    private attribute but the core's ``self._run``, and a run's fields (``run.t``,
    ``self._run.trace``, ...) are written by ``_run.py`` and the training modes alone (and the
    public ``t_`` setter of ``_core.py``)."""
    writers = {"sigmapi.model._run", *MODES}
    bad = []
    for m in sorted(n for n in MODULES if n.startswith("sigmapi.model.")):
        for a in _written(m):
            v = a.value
            on_run = (isinstance(v, ast.Name) and v.id == "run") or (
                isinstance(v, ast.Attribute) and v.attr == "_run"
            )
            if on_run and m not in writers and not (m.endswith("_core") and a.attr == "t"):
                bad.append(f"{m}:{a.lineno} writes the run's {a.attr}")
            if a.attr.startswith("_") and not (m.endswith("_core") and a.attr == "_run"):
                bad.append(f"{m}:{a.lineno} writes the private attribute {a.attr}")
    assert not bad, "\n".join(bad)


def _names_a_backend(node: ast.AST, backends: set[str]) -> bool:
    """Whether ``node`` picks a backend by its name: compares with one, passes one as
    ``backend=`` or stores one under the key ``"backend"``."""

    def named(n: ast.AST | None) -> bool:
        return isinstance(n, ast.Constant) and n.value in backends

    if isinstance(node, ast.Compare):
        return any(named(n) for n in (node.left, *node.comparators))
    if isinstance(node, ast.keyword):
        return node.arg == "backend" and named(node.value)
    if isinstance(node, ast.Dict):
        return any(
            isinstance(k, ast.Constant) and k.value == "backend" and named(v)
            for k, v in zip(node.keys, node.values, strict=True)
        )
    return False


def test_nothing_outside_the_kernels_names_a_backend_or_reads_its_state():
    """Only ``kernels/`` picks a backend by its name or reads the arrays of its state: the
    rest asks the kernel's interface (``COMPILES``, ``pair_cutoff``, ``weight_columns``,
    ``DEFINITION``, ``columns.version1_members``)."""
    from sigmapi.kernels import BACKENDS, columns

    bad = []
    for m, path in MODULES.items():
        if m.startswith("sigmapi.kernels"):
            continue
        for node in ast.walk(ast.parse(path.read_text("utf-8"))):
            if _names_a_backend(node, set(BACKENDS)):
                bad.append(f"{m}:{getattr(node, 'lineno', '?')} picks a backend by its name")
            if isinstance(node, ast.Constant) and node.value in columns.MEMBERS:
                bad.append(f"{m}:{node.lineno} reads the kernel state's {node.value!r}")
    assert not bad, "\n".join(bad)
