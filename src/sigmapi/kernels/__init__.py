"""Arithmetic backends of the Sigma-Pi SOM, one module per backend with the same functions.

``reference`` (dense NumPy, the definition), ``fast`` (numba, sparse codes and lazy decay) and
``gpu`` (torch, optional). :func:`get_backend` resolves a name; ``"auto"`` picks the fastest
one that imports.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from sigmapi.errors import ConfigError

__all__ = ["BACKENDS", "get_backend"]

BACKENDS = ("reference", "fast", "gpu")


def get_backend(name: str) -> ModuleType:
    """Return the kernel module called ``name`` (``"auto"``: fast if available, else reference)."""
    if name == "auto":
        try:
            return importlib.import_module("sigmapi.kernels.fast")
        except ImportError:
            return importlib.import_module("sigmapi.kernels.reference")
    if name not in BACKENDS:
        raise ConfigError(f"backend must be one of {('auto', *BACKENDS)}, got {name!r}")
    try:
        return importlib.import_module(f"sigmapi.kernels.{name}")
    except ImportError as exc:
        raise ConfigError(
            f"backend {name!r} is not available here ({exc}); install its extra "
            f"(pip install 'sigmapi[{name}]') or use backend='reference'"
        ) from None
