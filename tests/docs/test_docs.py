"""The documentation: the site builds with warnings as errors, the README is a front page.

The build is the README's documented command (``python -m sphinx -W --keep-going -b html docs
OUT``) into a temporary folder: the tutorial notebook executes, the results pages render their
tables from ``benchmarks/results/*.json``. The gallery's examples are run by
``tests/docs/test_examples.py`` already, so this build skips running them a second time
(``SIGMAPI_DOCS_GALLERY=False``); the documented command runs them.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
README = (ROOT / "README.md").read_text("utf-8")

pytest.importorskip("sphinx")
pytest.importorskip("myst_nb")
pytest.importorskip("sphinx_gallery")
sys.path.insert(0, str(DOCS / "_ext"))
import sigmapi_results  # noqa: E402


def test_readme_is_a_front_page():
    assert len(README.splitlines()) <= 150
    assert "python -m sphinx -W --keep-going -b html docs docs/_build/html" in README


def test_ci_runs_the_readme_test_command_then_the_slow_tests():
    command = "pip install -e '.[test]' && python -m pytest"
    assert command in README and "python -m pytest -m slow" in README
    ci = [ln for ln in (ROOT / ".ci" / "run").read_text("utf-8").splitlines() if ln.strip()]
    assert [ln.strip() for ln in ci[-2:]] == [command, "python -m pytest -m slow"]


def test_readme_headline_table_is_the_rendered_one():
    """The README's one table is the docs' ``headline`` table, rendered from the JSON."""
    rendered = sigmapi_results.TABLES["headline"]().markdown().split("\n\n")[0]
    assert rendered in README


def test_every_results_table_on_a_page_renders_and_names_its_files():
    used = set()
    for page in DOCS.rglob("*.md"):
        used |= set(re.findall(r"```\{results-table\} (\S+)", page.read_text("utf-8")))
    assert used and used <= set(sigmapi_results.TABLES)
    for name in sorted(used):
        table = sigmapi_results.TABLES[name]()
        assert table.rows, name
        assert all(len(r) == len(table.header) for r in table.rows), name
        assert all((ROOT / s).is_file() for s in table.sources), name


def test_result_values_follow_the_json(tmp_path, monkeypatch):
    """A table reads its numbers from the file: change the file and the table changes."""
    import json

    data = json.loads((ROOT / "benchmarks" / "results" / "files.json").read_text("utf-8"))
    data["bytes"]["v2"] = 12_345_678
    (tmp_path / "files.json").write_text(json.dumps(data), "utf-8")
    monkeypatch.setattr(sigmapi_results, "RESULTS", tmp_path)
    assert "12.3 MB" in sigmapi_results.TABLES["files"]().markdown()
    del data["bytes"]
    (tmp_path / "files.json").write_text(json.dumps(data), "utf-8")
    with pytest.raises(Exception, match="bytes"):
        sigmapi_results.TABLES["files"]()


@pytest.mark.slow  # about 100 s: .ci/run's second step runs it
def test_the_site_builds_with_warnings_as_errors(tmp_path):
    out = tmp_path / "html"
    env = {**os.environ, "SIGMAPI_DOCS_GALLERY": "False", "MPLBACKEND": "Agg"}
    r = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-b", "html", "-q",
         "-d", str(tmp_path / "doctrees"), str(DOCS), str(out)],
        capture_output=True, text=True, timeout=900, cwd=ROOT, env=env,
    )  # fmt: skip
    assert r.returncode == 0, (r.stdout + r.stderr)[-4000:]
    # the tutorial's kernel talks over encrypted sockets (docs/conf.py): no warning about TCP
    assert "without encryption" not in r.stdout + r.stderr
    for page in (
        "index",
        "getting-started",
        "tutorial",
        "api",
        "generated/sigmapi.SigmaPiSOM",
        "guide/index",
        "results/reproduction",
        "results/speed",
        "results/icub-history",
        "guide/icub",
        "auto_examples/index",
    ):
        assert (out / f"{page}.html").is_file(), page
    # the notebook ran: its last cell printed the compute it took
    assert re.search(r"compute: \d+ CPU seconds", (out / "tutorial.html").read_text("utf-8"))
    # a results page shows a number of its JSON, rendered by the build
    ceiling = sigmapi_results.load("ceiling-1d")["presets"]["paper-1d"]["summary"]
    cell = sigmapi_results.mw(ceiling["view_consistency"]).replace(" / ", "\u00a0/\u00a0")
    assert cell in (out / "results" / "reproduction.html").read_text("utf-8")
    # the equations are typeset by a MathJax the site serves itself: no page loads a script
    # from the network (a build here cannot rely on one, nor a reader offline)
    assert (out / "_static" / "mathjax" / "tex-chtml.js").is_file()
    algorithm = (out / "algorithm.html").read_text("utf-8")
    assert 'src="_static/mathjax/tex-chtml.js"' in algorithm
    assert algorithm.count('class="math') > 50  # the page's formulas are math, not code
    neurons = (out / "guide" / "neurons.html").read_text("utf-8")
    assert neurons.count('class="math') > 30 and "du_kd" not in neurons  # so are the neurons'
    remote = re.compile(r"<(?:script|link|img|iframe)\b[^>]*\b(?:src|href)=\"(?:https?:)?//")
    for page in out.rglob("*.html"):
        assert not remote.search(page.read_text("utf-8")), f"{page} loads from the network"
    # the API page of the estimator documents its methods, inherited ones included
    api = (out / "generated" / "sigmapi.SigmaPiSOM.html").read_text("utf-8")
    for method in ("fit", "partial_fit", "winner", "respond", "encode_views", "save"):
        assert f'id="sigmapi.SigmaPiSOM.{method}"' in api, method
    # every [docs] back-link of a highlighted source page lands on a documented object
    # (docs/_ext/sigmapi_viewcode.py)
    ids: dict[Path, set[str]] = {}
    for page in (out / "_modules").rglob("*.html"):
        for url, anchor in re.findall(r'class="viewcode-back" href="([^"#]+)#([^"]+)"',
                                      page.read_text("utf-8")):  # fmt: skip
            target = (page.parent / url).resolve()
            if target not in ids:
                ids[target] = set(re.findall(r'id="([^"]+)"', target.read_text("utf-8")))
            assert anchor in ids[target], f"{page.relative_to(out)}: {url}#{anchor}"
