"""The package version: written here once; ``pyproject.toml`` reads it (``dynamic =
["version"]``, ``[tool.setuptools.dynamic]``), so that the source tree, an editable install
and a built wheel all say the same."""

from __future__ import annotations

__all__ = ["__version__"]

__version__ = "0.1.0"
