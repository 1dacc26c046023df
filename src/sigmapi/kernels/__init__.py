"""The arithmetic of the Sigma-Pi SOM behind one contract, and the registry of backends.

- :mod:`~sigmapi.kernels.base`: the contract, :class:`Kernel` (what every backend offers:
  its state, memory, model file arrays, activations, winners, neighbourhood, training, plain
  and gated), and :class:`KernelBase`, the generic defaults a backend subclasses so that it
  implements only its arithmetic; :class:`BackendOptions` (device, dtype);
- :mod:`~sigmapi.kernels.reference`: dense NumPy, written to be read (the definition);
- :mod:`~sigmapi.kernels.fast`: numba, sparse codes and lazy decay (its file layout, readable
  without numba: :mod:`~sigmapi.kernels.columns`).

Kernels compute on the map as one value, :class:`~sigmapi.rules.geometry.MapGeometry`
(grid, periodic axes, the soft winner's window; ``SOMConfig.geometry``; also importable from
here, with everything else a backend needs).

:data:`REGISTRY` maps names to kernels (instances); :data:`BACKENDS` lists the names;
:func:`get_backend` returns one (``"auto"``: the fast kernel, or the reference where numba
does not import), with options if given; :func:`register_backend` adds one. Other packages
add backends through the entry-point group ``sigmapi.kernels`` (:data:`ENTRY_POINT_GROUP`):
an entry point named ``NAME`` that loads a kernel (an object satisfying :class:`Kernel`,
usually an instance of a :class:`KernelBase` subclass, whose ``NAME`` is the entry point's
name), e.g. in the plugin's ``pyproject.toml``::

    [project.entry-points."sigmapi.kernels"]
    torch = "sigmapi_torch.kernel:KERNEL"

Entry points are read once, the first time the names are needed; a backend's module is
imported only when the backend is first used.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Callable, Collection, Iterator
from dataclasses import dataclass
from importlib.metadata import entry_points
from typing import Any

from numpy import float64
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.errors import ConfigError
from sigmapi.kernels import columns, reference
from sigmapi.kernels.base import (
    CONTRACT,
    BackendOptions,
    FileArrays,
    Kernel,
    KernelBase,
    KernelState,
    dense_file_weights,
)
from sigmapi.rules.geometry import MapGeometry

__all__ = [
    "BACKENDS",
    "BACKEND_CHOICES",
    "DEFINITION",
    "ENTRY_POINT_GROUP",
    "REGISTRY",
    "BackendOptions",
    "Kernel",
    "KernelBase",
    "KernelState",
    "MapGeometry",
    "file_weights",
    "get_backend",
    "register_backend",
]

ENTRY_POINT_GROUP = "sigmapi.kernels"
"""The entry-point group other packages register backends in."""


@dataclass(frozen=True)
class _Lazy:
    """A backend not imported yet: ``load()`` imports it; ``needs`` names what it needs."""

    load: Callable[[], Any]
    needs: str


def _import_fast() -> Kernel[Any]:
    from sigmapi.kernels import fast

    return fast.KERNEL


REGISTRY: dict[str, Kernel[Any] | _Lazy] = {
    "reference": reference.KERNEL,
    "fast": _Lazy(_import_fast, "numba"),
}
"""The backends by name: kernels, or loaders of those not imported yet (the fast kernel until
first use, entry points)."""

DEFINITION = reference.NAME
"""The kernel that is the definition (dense NumPy, compiles nothing): the backend a short run
takes where its speed does not matter."""

AUTO = ("fast", "reference")
"""What ``backend="auto"`` picks: the first of these that imports here."""

_NAME = re.compile(r"^[a-z][a-z0-9_]{0,31}$")
_discovered = False


def _discover() -> None:
    """Add the backends of the entry-point group, once (not importing them)."""
    global _discovered
    if _discovered:
        return
    _discovered = True
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        if ep.name in REGISTRY or not _NAME.match(ep.name):
            warnings.warn(
                f"entry point {ep.name!r} ({ep.value}) of group {ENTRY_POINT_GROUP!r} is "
                "ignored: the name is taken or not a lower-case identifier",
                stacklevel=3,
            )
            continue
        REGISTRY[ep.name] = _Lazy(ep.load, f"the package of entry point {ep.value!r}")


class _Names(Collection[str]):
    """The registered backends' names after ``first``, read when used (a backend registered
    later counts)."""

    def __init__(self, first: tuple[str, ...] = ()) -> None:
        self._first = first

    def _names(self) -> tuple[str, ...]:
        _discover()
        return (*self._first, *REGISTRY)

    def __iter__(self) -> Iterator[str]:
        return iter(self._names())

    def __len__(self) -> int:
        return len(self._names())

    def __contains__(self, name: object) -> bool:
        return name in self._names()

    def __repr__(self) -> str:
        return repr(self._names())


BACKENDS: Collection[str] = _Names()
"""The names of the backends (``"auto"`` picks one of them, see :data:`AUTO`)."""
BACKEND_CHOICES: Collection[str] = _Names(("auto",))
"""What a ``backend`` setting accepts: ``"auto"`` and :data:`BACKENDS`."""


def _check(name: str, kernel: Any) -> Kernel[Any]:
    missing = [n for n in CONTRACT if not hasattr(kernel, n)]
    if missing:
        raise ConfigError(
            f"backend {name!r} lacks {missing} of the kernel contract "
            "(sigmapi.kernels.base.Kernel); define them"
        )
    if kernel.NAME != name:
        raise ConfigError(f"backend {name!r} has NAME {kernel.NAME!r}; they must be the same")
    return kernel


def register_backend(name: str, kernel: Kernel[Any]) -> None:
    """Add ``kernel`` (an object satisfying :class:`Kernel`, e.g. an instance of a
    :class:`KernelBase` subclass) as backend ``name``.

    ``name`` must be a lower-case identifier not taken (``"auto"`` never is free) and equal
    to ``kernel.NAME``, which model files record. Raises :class:`~sigmapi.errors.ConfigError`
    naming the problem.
    """
    _discover()
    if not isinstance(name, str) or not _NAME.match(name) or name == "auto":
        raise ConfigError(
            f"backend name must be a lower-case identifier other than 'auto', got {name!r}"
        )
    if name in REGISTRY and REGISTRY[name] is not kernel:
        raise ConfigError(f"backend {name!r} is registered already; choose another name")
    REGISTRY[name] = _check(name, kernel)


def _load(name: str) -> Kernel[Any]:
    """The kernel of registered backend ``name``, importing it on first use (ImportError if
    it does not import here)."""
    entry = REGISTRY[name]
    if isinstance(entry, _Lazy):
        kernel = _check(name, entry.load())
        REGISTRY[name] = kernel
        return kernel
    return entry


def get_backend(name: str, options: BackendOptions | None = None) -> Kernel[Any]:
    """The kernel called ``name``: ``"auto"`` (the first of :data:`AUTO` that imports here) or
    one of :data:`BACKENDS`; a ConfigError if it is none of them or does not import here.

    ``options``: its settings (:class:`BackendOptions`; None: its defaults), checked by the
    kernel (a ConfigError names what it takes)."""
    kernel = _find(name)
    return kernel if options is None else kernel.with_options(options)


def _find(name: str) -> Kernel[Any]:
    _discover()
    _validate.choice("backend", name, BACKEND_CHOICES)
    if name == "auto":
        for candidate in AUTO[:-1]:
            try:
                return _load(candidate)
            except ImportError:  # numba missing or broken on this machine: the next one
                continue
        return _load(AUTO[-1])
    entry = REGISTRY[name]
    try:
        return _load(name)
    except ImportError:
        needs = entry.needs if isinstance(entry, _Lazy) else "its dependencies"
        raise ConfigError(
            f"backend {name!r} needs {needs}, which does not import here; "
            f"install {needs} or use backend='reference'"
        ) from None


def _available(name: object) -> Kernel[Any] | None:
    """The kernel of backend ``name`` if it is registered and imports here, else None."""
    _discover()
    if not isinstance(name, str) or name not in REGISTRY:
        return None
    try:
        return _load(name)
    except ImportError:
        return None


def file_weights(
    writer: object, shape: tuple[int, int, int], arrays: FileArrays
) -> NDArray[float64]:
    """Dense float64 weights ``shape`` of a model file's ``arrays``, written by backend
    ``writer`` (the name in the file's header; None if it names none).

    Read by the writer where it is here; else by the layouts sigmapi's own backends write,
    which read without them (dense ``weights``; the fast kernel's columns, without numba).
    Raises ``ValueError`` if the arrays do not make weights of ``shape``.
    """
    kernel = _available(writer)
    if kernel is not None:
        return kernel.file_weights(shape, arrays)
    if set(arrays) == {"weights"}:
        return dense_file_weights(shape, arrays)
    if "state_raw" in arrays:
        return columns.file_weights(shape, arrays)
    raise ValueError(
        f"the file was written by backend {writer!r}, which is not available here, in a layout "
        f"of its own ({sorted(arrays)}); install that backend to read it"
    )
