"""On a fresh machine: the README's documentation command in a virtual environment with only
the docs extra, and the built wheel in one with nothing but itself (slow: each installs its
dependencies from the package index; ``python -m pytest -m slow tests/docs/test_fresh_env.py``).

The packaging itself (one version, SPDX licence, an sdist without tests) is checked fast.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
README = (ROOT / "README.md").read_text("utf-8")
DOCS_COMMAND = (
    "pip install -e '.[docs]' && python -m sphinx -W --keep-going -b html docs docs/_build/html"
)
REMOTE = re.compile(r"<(?:script|link|img|iframe)\b[^>]*\b(?:src|href)=\"(?:https?:)?//")
_BUILT = ("_build", "auto_examples", "generated", "__pycache__", "*.egg-info", ".git", "dist",
          "build", ".pytest_cache", ".mypy_cache", ".ruff_cache", ".hypothesis",
          ".venv")  # fmt: skip


def _venv(where: Path) -> dict[str, str]:
    """A fresh virtual environment at ``where``; the environment variables that use it (and
    nothing of the test run's: no PYTHONPATH, no docs switches)."""
    subprocess.run([sys.executable, "-m", "venv", str(where)], check=True, timeout=300)
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "MPLBACKEND", "VIRTUAL_ENV")
           and not k.startswith("SIGMAPI_")}  # fmt: skip
    env["PATH"] = f"{where / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    env["VIRTUAL_ENV"] = str(where)
    return env


def _clone(dst: Path) -> Path:
    """The checkout's files without what builds and runs leave behind."""
    shutil.copytree(ROOT, dst, ignore=shutil.ignore_patterns(*_BUILT))
    return dst


def _run(cmd: str, cwd: Path, env: dict[str, str], timeout: int) -> str:
    r = subprocess.run(["bash", "-c", cmd], cwd=cwd, env=env, capture_output=True, text=True,
                       timeout=timeout)  # fmt: skip
    assert r.returncode == 0, f"{cmd} exited {r.returncode}:\n{(r.stdout + r.stderr)[-6000:]}"
    return r.stdout + r.stderr


def test_the_version_is_written_once_and_the_licence_is_spdx():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text("utf-8"))
    meta, tool = project["project"], project["tool"]["setuptools"]
    assert "version" not in meta and meta["dynamic"] == ["version"]
    assert tool["dynamic"]["version"] == {"attr": "sigmapi._version.__version__"}
    assert meta["license"] == "MIT" and meta["license-files"] == ["LICENSE"]
    assert not any(c.startswith("License ::") for c in meta.get("classifiers", []))
    assert "setuptools>=77" in project["build-system"]["requires"]
    # the sdist ships no tests (they read docs/, examples/, benchmarks/ of a clone)
    manifest = (ROOT / "MANIFEST.in").read_text("utf-8").split()
    assert "tests" in manifest[manifest.index("prune") :]


@pytest.mark.slow
def test_the_readme_docs_command_works_with_only_the_docs_extra(tmp_path):
    assert DOCS_COMMAND in README
    env = _venv(tmp_path / "venv")
    repo = _clone(tmp_path / "sigmapi")
    _run(DOCS_COMMAND, repo, env, timeout=3000)
    html = repo / "docs" / "_build" / "html"
    assert (html / "_static" / "mathjax" / "tex-chtml.js").is_file()
    for page in html.rglob("*.html"):
        assert not REMOTE.search(page.read_text("utf-8")), f"{page} loads from the network"
    # the examples whose extra the docs extra does not install are shown, and say so
    for name, extra in (("compare_baselines", "baselines"), ("robot", "robot")):
        text = (html / "auto_examples" / f"{name}.html").read_text("utf-8")
        assert "was not run when this site was built" in text and extra in text, name
    ran = (html / "auto_examples" / "own_data.html").read_text("utf-8")
    assert "was not run" not in ran


@pytest.mark.slow
def test_the_built_wheel_installs_alone_and_runs_the_quickstart(tmp_path):
    build_env = _venv(tmp_path / "build-venv")
    repo = _clone(tmp_path / "sigmapi")
    log = _run("pip install -q build && python -m build -o dist .", repo, build_env, 1200)
    assert not re.search(r"deprecat", log, re.IGNORECASE), log[-4000:]
    wheel = next((repo / "dist").glob("sigmapi-*.whl"))
    sdist = next((repo / "dist").glob("sigmapi-*.tar.gz"))
    listing = subprocess.run(["tar", "tzf", str(sdist)], capture_output=True, text=True,
                             check=True).stdout  # fmt: skip
    assert "/tests/" not in listing and "/src/sigmapi/model/som.py" in listing
    env = _venv(tmp_path / "venv")
    _run(f"pip install -q '{wheel}'", tmp_path, env, 1200)
    quickstart = re.search(r"## Quickstart\n\n```python\n(.*?)```", README, re.S)
    assert quickstart is not None
    work = tmp_path / "work"
    work.mkdir()
    (work / "quickstart.py").write_text(quickstart.group(1), "utf-8")
    out = _run("python quickstart.py && sigmapi --version", work, env, 1800)
    assert (work / "paper-1d.npz").is_file()
    version = wheel.name.split("-")[1]
    assert f"sigmapi {version}" in out
    # the same unit for the two views of z = 0.5, as the README's comment says
    assert re.search(r"\[(\d+) \1\]", out), out
