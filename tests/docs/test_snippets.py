"""Every code block of the README and of the docs runs as written, so a snippet that fails as
written fails the suite.

Each page is one session, like a doctest: its blocks run in order, in a fresh temporary
working folder, the Python blocks in one namespace, so a block may use what an earlier one
defined or wrote (``map.npz`` of the export page's shell block is read by its Python block).

What a block's fence language means here (any other language fails the test: a block that is
not meant to run says so by its language, none is skipped silently):

- ``python``: executed.
- ``bash``: each command (continuation lines joined, ``&&`` split, comments dropped):

  - ``sigmapi train``, ``evaluate``, ``presets``, ``figure`` and ``export`` run in-process
    (``sigmapi.cli.main``) and must exit 0;
  - every other ``sigmapi`` command (the experiments: ``reproduce``, ``reach``, ``icub``, ...,
    minutes to hours as documented) is parsed by the real parser, so an option or value the
    command does not take fails; their runs are the experiments' own tests
    (``tests/experiments/``, ``tests/cli/``, ``tests/envs/``, each at ``--quick`` or smaller);
  - ``pip install`` lines: every extra they name is an extra of ``pyproject.toml``; the
    installs themselves run in fresh virtual environments in ``tests/docs/test_fresh_env.py``
    (slow);
  - ``python benchmarks/X.py --opt ...``: the script exists and takes every option given
    (the benchmarks are measurements of minutes to hours, run by hand; their JSON is read by
    the results pages, ``tests/docs/test_docs.py``);
  - ``python -m pytest`` is the test run itself (``.ci/run``), ``python -m sphinx ...`` the
    site build (``test_the_site_builds_with_warnings_as_errors``, slow), ``ruff``/``mypy`` the
    linters of the development page, run before each commit; these are checked to be the
    commands ``.ci/run`` and ``pyproject.toml`` configure, not run here.
- ``toml``: parsed, and a sweep spec is read by the sweep's own loader.
- ``text`` (a file tree, program output) and ``bibtex``: not code, not run.
- ``{code-cell}`` blocks (``docs/tutorial.md``, a MyST-NB notebook) run in the site build,
  which fails on a cell that raises (``nb_execution_raise_on_error``), not here again.

**Cheap runs of long snippets.** The quickstart fits ``paper-1d`` as shipped: 300,000
iterations and the refinement, seconds to minutes per fit. Here every preset is read with at
most :data:`ITERATIONS` iterations and :data:`REFINE_PAIRS` refinement pairs (the fixture
``short_presets`` wraps the preset reader, ``sigmapi.config._from_toml`` for a preset), and a
first-order map's :class:`~sigmapi.neurons.training.TrainingConfig` defaults to
:data:`NEURON_PAIRS` pairs. The code paths are those of the full runs; only the lengths are
smaller. A snippet that gives an explicit length (``partial_fit(iterations=10_000)``) runs it.
"""

from __future__ import annotations

import dataclasses
import re
import shlex
import tomllib
from dataclasses import dataclass
from pathlib import Path

import pytest

from sigmapi import config as config_module
from sigmapi.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
PAGES = [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]

ITERATIONS = 1000
"""Training iterations of every preset in the snippet runs (the shipped ones: 20,000-300,000)."""
REFINE_PAIRS = 1000
"""Pairs per refinement round of every preset in the snippet runs (shipped: 100,000-300,000)."""
NEURON_PAIRS = 2000
"""Pairs of the online phase and of each batch step of a first-order map (default 100,000)."""

PYTHON = {"python"}
SHELL = {"bash"}
PARSED = {"toml"}
NOT_CODE = {"text", "bibtex"}
NOTEBOOK = {"{code-cell}"}
DIRECTIVES = {"{figure}", "{image}", "{toctree}", "{results-table}", "{eval-rst}"}
"""MyST directives that are no code block: a figure, a table of contents, a rendered table."""

RUN = {"train", "evaluate", "presets", "figure", "export"}
"""The ``sigmapi`` commands run in-process; the others are parsed (see the module docstring)."""


@dataclass(frozen=True)
class Block:
    language: str
    line: int
    text: str


def blocks(page: Path) -> list[Block]:
    """The fenced blocks of ``page`` in order: language (a ``{code-block} LANG`` directive is
    LANG; other directives keep their name), the line of the opening fence, the body."""
    lines = page.read_text("utf-8").splitlines()
    found, i = [], 0
    while i < len(lines):
        m = re.match(r"^\s*(`{3,}|~{3,})(.*)$", lines[i])
        if not m:
            i += 1
            continue
        fence, info = m.group(1), m.group(2).split()
        end = i + 1
        close = re.compile(rf"^\s*{re.escape(fence[0])}{{{len(fence)},}}\s*$")
        while end < len(lines) and not close.match(lines[end]):
            end += 1
        language = info[0] if info else ""
        if language == "{code-block}":
            language = info[1] if len(info) > 1 else ""
        body = [ln for ln in lines[i + 1 : end] if not re.match(r"^:\w[\w-]*:", ln)]
        found.append(Block(language, i + 1, "\n".join(body)))
        i = end + 1
    return found


def indented_code(page: Path) -> list[int]:
    """The lines that open an indented (unfenced) code block: 4 spaces after a blank line
    outside a fence and outside a list. Such a block has no language, so it says neither
    what it is nor whether it runs."""
    lines = page.read_text("utf-8").splitlines()
    found, fence, in_list = [], None, False
    for n, line in enumerate(lines, 1):
        m = re.match(r"^\s*(`{3,}|~{3,})", line)
        if m and (fence is None or m.group(1)[0] == fence):
            fence = None if fence else m.group(1)[0]
            continue
        if fence or not line.strip():
            continue
        if re.match(r"^(?:[-*+]|\d+\.)\s", line):
            in_list = True
        elif not line.startswith(" "):
            in_list = False
        if line.startswith("    ") and not in_list and n > 1 and not lines[n - 2].strip():
            found.append(n)
    return found


def commands(text: str) -> list[list[str]]:
    """The commands of a shell block: continuation lines joined, comments dropped, ``&&``
    split, each as its argv."""
    joined = re.sub(r"\\\n\s*", " ", text)
    out = []
    for line in joined.splitlines():
        words = shlex.split(line, comments=True)
        while words:
            cut = words.index("&&") if "&&" in words else len(words)
            if words[:cut]:
                out.append(words[:cut])
            words = words[cut + 1 :]
    return out


def _extras() -> set[str]:
    data = tomllib.loads((ROOT / "pyproject.toml").read_text("utf-8"))
    return set(data["project"]["optional-dependencies"])


def check_shell(argv: list[str], where: str) -> None:
    """Run, parse or check one documented shell command (the module docstring says which)."""
    if argv[0] == "sigmapi":
        if argv[1] in RUN:
            assert main(argv[1:]) == 0, f"{where}: {shlex.join(argv)} failed"
        elif argv[-1] == "--help":
            with pytest.raises(SystemExit) as exc:
                main(argv[1:])
            assert exc.value.code == 0, where
        else:
            build_parser().parse_args(argv[1:])  # an unknown option exits 2: fails the test
        return
    if argv[:2] == ["pip", "install"]:
        for spec in argv[2:]:
            if spec == "-e":
                continue
            m = re.fullmatch(r"\.(?:\[([\w,-]+)\])?", spec)
            assert m, f"{where}: pip installs {spec!r}, not this project"
            assert set((m.group(1) or "").split(",")) - {""} <= _extras(), f"{where}: {spec}"
        return
    if argv[0] == "python" and argv[1].startswith("benchmarks/"):
        script = ROOT / argv[1]
        assert script.is_file(), f"{where}: no {argv[1]}"
        source = script.read_text("utf-8")
        for option in (a.split("=")[0] for a in argv[2:] if a.startswith("--")):
            assert f'"{option}"' in source, f"{where}: {argv[1]} takes no {option}"
        return
    ci = (ROOT / ".ci" / "run").read_text("utf-8")
    if argv[:3] == ["python", "-m", "pytest"]:
        assert shlex.join(argv) in ci, where
    elif argv[:3] == ["python", "-m", "sphinx"]:
        assert shlex.join(argv) in (ROOT / "README.md").read_text("utf-8"), where
    elif argv[0] in ("ruff", "mypy"):
        assert f"[tool.{argv[0]}" in (ROOT / "pyproject.toml").read_text("utf-8"), where
    else:
        pytest.fail(f"{where}: no check for the shell command {shlex.join(argv)!r}")


def check_toml(text: str, where: str) -> None:
    data = tomllib.loads(text)
    if "grid" in data:  # a sweep spec: the sweep reads it
        from sigmapi.experiments.sweep.run import SweepSpec

        assert SweepSpec.from_toml(text, where).count() > 0, where


@pytest.fixture
def short_presets(monkeypatch):
    """Every preset read with at most ITERATIONS iterations and REFINE_PAIRS refinement pairs,
    and first-order maps trained on NEURON_PAIRS pairs (see the module docstring)."""
    read = config_module._from_toml

    def short(data, source, base=None):
        cfg = read(data, source, base)
        if not source.startswith("preset "):
            return cfg
        return cfg.replace(
            iterations=min(cfg.iterations, ITERATIONS),
            refine_pairs=min(cfg.refine_pairs, REFINE_PAIRS),
        )

    monkeypatch.setattr(config_module, "_from_toml", short)
    from sigmapi.neurons import training

    @dataclasses.dataclass(frozen=True)
    class ShortTraining(training.TrainingConfig):
        pairs: int = NEURON_PAIRS
        refine_pairs: int = NEURON_PAIRS

    ShortTraining.__name__ = ShortTraining.__qualname__ = "TrainingConfig"
    monkeypatch.setattr(training, "TrainingConfig", ShortTraining)


def _page_id(page: Path) -> str:
    return str(page.relative_to(ROOT))


def test_every_block_has_a_language_this_test_knows():
    """A block with no language, or one this test does not know, fails: a snippet that is not
    meant to run is marked so (``text``), none is skipped without a word."""
    known = PYTHON | SHELL | PARSED | NOT_CODE | NOTEBOOK | DIRECTIVES
    unknown = [
        f"{_page_id(p)}:{b.line} [{b.language}]"
        for p in PAGES
        for b in blocks(p)
        if b.language not in known
    ]
    assert not unknown, unknown
    indented = [f"{_page_id(p)}:{n}" for p in PAGES for n in indented_code(p)]
    assert not indented, f"an indented code block: fence it with its language, {indented}"
    runs = [b for p in PAGES for b in blocks(p) if b.language in PYTHON | SHELL]
    assert len(runs) > 30  # the parser found the blocks


def test_the_block_reader_follows_the_fences(tmp_path):
    page = "\n".join(
        ["# t", "```python", "a = 1", "```", "```{code-block} bash", ":caption: x",
         "sigmapi presets \\", "  # c", "```", "````text", "```", "````"]
    )  # fmt: skip
    path = tmp_path / "p.md"
    path.write_text(page, "utf-8")
    got = blocks(path)
    assert [(b.language, b.line) for b in got] == [("python", 2), ("bash", 5), ("text", 10)]
    assert got[1].text == "sigmapi presets \\\n  # c" and got[2].text == "```"
    assert commands("sigmapi a --x 1 \\\n   --y 2 && sigmapi b  # c\n# only\n") == [
        ["sigmapi", "a", "--x", "1", "--y", "2"],
        ["sigmapi", "b"],
    ]


def test_a_snippet_that_fails_as_written_fails(tmp_path, monkeypatch):
    """The runner can fail: a block using a name an earlier block does not define raises."""
    page = tmp_path / "page.md"
    page.write_text("```python\nprint(cfg)\n```\n```python\ncfg = 1\n```\n", "utf-8")
    with pytest.raises(NameError, match="cfg"):
        run_page(page, tmp_path, monkeypatch)
    page.write_text("```bash\nsigmapi train --preset paper-1d --no-such-option\n```\n", "utf-8")
    with pytest.raises(SystemExit):
        run_page(page, tmp_path, monkeypatch)
    page.write_text("```bash\npip install '.[no-such-extra]'\n```\n", "utf-8")
    with pytest.raises(AssertionError, match="no-such-extra"):
        run_page(page, tmp_path, monkeypatch)


def run_page(page: Path, folder: Path, monkeypatch) -> int:
    """Run the blocks of ``page`` in order in ``folder``; the number of blocks run."""
    monkeypatch.chdir(folder)
    namespace: dict[str, object] = {"__name__": "__snippet__"}
    n = 0
    for block in blocks(page):
        where = f"{page.name}:{block.line}"
        if block.language in PYTHON:
            exec(compile(block.text, where, "exec"), namespace)
        elif block.language in SHELL:
            for argv in commands(block.text):
                check_shell(argv, where)
        elif block.language in PARSED:
            check_toml(block.text, where)
        else:
            continue
        n += 1
    return n


@pytest.mark.parametrize(
    "page",
    [p for p in PAGES if any(b.language in PYTHON | SHELL | PARSED for b in blocks(p))],
    ids=_page_id,
)
def test_the_page_runs_as_written(page, tmp_path, monkeypatch, short_presets):
    assert run_page(page, tmp_path, monkeypatch) > 0
