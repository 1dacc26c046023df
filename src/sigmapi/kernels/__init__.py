"""The arithmetic of the Sigma-Pi SOM behind one contract, and the registry of backends.

- :mod:`~sigmapi.kernels.base`: the contract, :class:`Kernel` (the functions every backend
  module offers, with shapes) and :class:`KernelState`;
- :mod:`~sigmapi.kernels.reference`: dense NumPy, written to be read (the definition);
- :mod:`~sigmapi.kernels.fast`: numba, sparse codes and lazy decay.

:data:`BACKENDS` names them; :func:`get_backend` returns one (``"auto"``: the fast one).
"""

from __future__ import annotations

from typing import Any

from sigmapi import _validate
from sigmapi.errors import ConfigError
from sigmapi.kernels import reference
from sigmapi.kernels.base import Kernel, KernelState

__all__ = ["BACKENDS", "Kernel", "KernelState", "get_backend"]

BACKENDS = ("reference", "fast")
"""The kernels that exist (``"auto"`` picks ``"fast"``)."""


def get_backend(name: str) -> Kernel[Any]:
    """The kernel module called ``name``, one of ``"auto"`` (the fast one) and :data:`BACKENDS`."""
    _validate.choice("backend", name, ("auto", *BACKENDS))
    kernel: Kernel[Any] = reference
    if name != "reference":
        try:
            from sigmapi.kernels import fast
        except ImportError:  # numba missing or broken on this machine: "auto" falls back
            if name == "fast":
                raise ConfigError(
                    "backend 'fast' needs numba, which does not import here; "
                    "install numba or use backend='reference'"
                ) from None
        else:
            kernel = fast
    return kernel
