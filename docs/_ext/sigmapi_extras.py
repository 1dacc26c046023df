"""The gallery on a machine without every extra: an example whose extra is not installed is
shown, not run, and its page says why.

An example names the extra it needs in its docstring (``Needs the extra: ``pip install
'sigmapi[NAME]'````). The extra's requirements are read from ``pyproject.toml`` (the
checkout's own), and an extra counts as installed when every distribution it names is.
:func:`gallery_pattern` gives sphinx-gallery's ``filename_pattern`` (the examples to run);
:func:`note_skipped` adds the note to the page of each example that is not run.
"""

from __future__ import annotations

import re
import tomllib
from functools import cache
from importlib import metadata
from pathlib import Path

__all__ = ["gallery_pattern", "missing_extra", "note_skipped", "skipped_examples"]

NEEDS = re.compile(r"Needs the extra: ``pip install 'sigmapi\[(\w+)\]'``")
_NAME = re.compile(r"^\s*([A-Za-z0-9][A-Za-z0-9._-]*)(?:\[([^\]]*)\])?")


@cache
def _extras(pyproject: Path) -> dict[str, tuple[str, ...]]:
    data = tomllib.loads(pyproject.read_text("utf-8"))
    return {k: tuple(v) for k, v in data["project"]["optional-dependencies"].items()}


def _installed(requirement: str, extras: dict[str, tuple[str, ...]]) -> bool:
    m = _NAME.match(requirement)
    if m is None:
        return False
    name, inner = m.group(1), m.group(2)
    if name.lower() == "sigmapi":  # an extra that names others
        return all(_extra_installed(e.strip(), extras) for e in (inner or "").split(",") if e)
    try:
        metadata.version(name)
    except metadata.PackageNotFoundError:
        return False
    return True


def _extra_installed(extra: str, extras: dict[str, tuple[str, ...]]) -> bool:
    return extra in extras and all(_installed(r, extras) for r in extras[extra])


def missing_extra(example: Path, pyproject: Path) -> str | None:
    """The extra ``example`` needs and this environment lacks, else None."""
    m = NEEDS.search(example.read_text("utf-8"))
    if m is None:
        return None
    extra = m.group(1)
    return None if _extra_installed(extra, _extras(pyproject)) else extra


def skipped_examples(examples: Path, pyproject: Path) -> dict[str, str]:
    """``{stem: extra}`` of the examples not to run here."""
    out = {}
    for src in sorted(examples.glob("*.py")):
        extra = missing_extra(src, pyproject)
        if extra is not None:
            out[src.stem] = extra
    return out


def gallery_pattern(skipped: dict[str, str]) -> str:
    """sphinx-gallery's ``filename_pattern``: every example but the skipped ones."""
    if not skipped:
        return r".*\.py$"
    names = "|".join(re.escape(s) for s in sorted(skipped))
    return rf"(^|[\\/])(?!(?:{names})\.py$)[^\\/]+\.py$"


def note_skipped(skipped: dict[str, str], docname: str, source: list[str]) -> None:
    """Sphinx ``source-read``: a note under the title of a skipped example's page."""
    folder, _, stem = docname.rpartition("/")
    if folder != "auto_examples" or stem not in skipped:
        return
    extra = skipped[stem]
    note = (
        "\n.. note::\n\n"
        f"   This example was not run when this site was built: it needs the ``{extra}`` "
        f"extra, which the build's environment lacks (``pip install 'sigmapi[{extra}]'``, "
        "then build again). Its code is shown as it is.\n\n"
    )
    lines = source[0].split("\n")
    for i in range(1, len(lines)):
        under = lines[i].strip()
        if under and set(under) == {"="} and len(under) >= len(lines[i - 1].strip()) > 0:
            lines.insert(i + 1, note)
            source[0] = "\n".join(lines)
            return
    source[0] = note + source[0]
