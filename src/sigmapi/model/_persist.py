"""The estimator as arrays, files and pickles: :class:`PersistMixin`.

What a model file holds is decided by :mod:`sigmapi.model.file` (it validates the parts and
never imports the estimator) and how it is written by :mod:`sigmapi.io` (atomic, verified,
never pickled); this mixin gives :class:`sigmapi.SigmaPiSOM` its ``to_arrays`` /
``from_arrays``, ``save`` / ``load`` and the pickle hooks, which store the same arrays.
"""

from __future__ import annotations

import copy
import os
from pathlib import Path
from typing import Any, Self

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.config import BACKEND_NAMES, SOMConfig
from sigmapi.errors import ConfigError
from sigmapi.model._core import MapCore
from sigmapi.model.file import read_parts, write_parts

__all__ = ["PersistMixin"]

_BACKEND_FIX = "the backend to load the model onto, or None for the one that wrote it"


class PersistMixin(MapCore):
    """Arrays, files and pickles of an estimator with ``config``, ``t_`` and a kernel state."""

    def to_arrays(self) -> tuple[dict[str, object], dict[str, NDArray[Any]]]:
        """The model as a JSON-able header and arrays (what a model file holds).

        The header holds the resolved ``config``, the iteration count ``t``, the
        ``seed_entropy`` of the random streams (a decimal string) and the ``backend``; the
        arrays are the backend's own, in its precision, with which the model continues bit
        for bit on that backend (:mod:`sigmapi.model.file`).

        Raises :class:`~sigmapi.errors.NumericalError` if the weights hold NaN or inf, so
        that no file is written that :func:`sigmapi.load` would refuse.
        """
        run = self._run
        return write_parts(
            self.config,
            self.t_,
            self.seed_entropy,
            run.kernel,
            run.fitted(),
            run.refined,
            run.refine_rows,
        )

    @classmethod
    def from_arrays(
        cls,
        header: dict[str, Any],
        arrays: dict[str, NDArray[Any]],
        backend: str | None = None,
        source: str = "arrays",
    ) -> Self:
        """Rebuild a model from :meth:`to_arrays`'s header and arrays (also of older files).

        ``backend`` runs the model on another kernel (which starts from the weights; the
        kernel state is used only by the backend that wrote it). Raises
        :class:`~sigmapi.errors.ModelFileError`, its message starting with ``source``, if
        the header and arrays do not make a model (:func:`sigmapi.model.file.read_parts`).
        """
        if backend is not None:  # the caller's mistake, not the file's: said before reading
            _validate.choice("backend", backend, BACKEND_NAMES, fix=_BACKEND_FIX)
        parts = read_parts(header, arrays, backend, source)
        model = cls(parts.config)
        model.seed_entropy = parts.seed_entropy
        run = model._run
        state = parts.state
        if state is None:
            state = run.prepared(np.asarray(parts.weights), model.config.kernel_tol)
        run.restore(state, parts.t, parts.refined, parts.refine_rows)
        return model

    def save(self, path: str | Path, *, compress: bool = False) -> Path:
        """Write the model atomically to ``path`` (``.npz``, no pickle); returns the path.

        ``compress=True`` deflates the arrays (for archives: smaller, slower). The ``.npz``
        file is the format to keep models in; ``pickle`` works (it stores the same arrays)
        but ties a file to Python and is never safe to load from others.
        """
        from sigmapi.io import write_model

        return write_model(path, *self.to_arrays(), compress=compress)

    @classmethod
    def load(cls, path: str | Path, backend: str | None = None) -> Self:
        """Read a model written by :meth:`save` (optionally onto another ``backend``)."""
        from sigmapi.io import read_model

        if not isinstance(path, (str, os.PathLike)) or isinstance(path, bytes):
            shown = repr(path[:40]) if isinstance(path, (bytes, bytearray)) else repr(path)[:60]
            raise ConfigError(
                f"path must be a file name (str or pathlib.Path), got {type(path).__name__} "
                f"{shown}; give the model file's name (a name in bytes: name.decode())"
            )
        if backend is not None:
            _validate.choice("backend", backend, BACKEND_NAMES, fix=_BACKEND_FIX)
        header, arrays = read_model(path)
        return cls.from_arrays(header, arrays, backend=backend, source=str(path))

    def __getstate__(self) -> dict[str, object]:
        """State arrays and the config, never modules or compiled kernels (see :meth:`save`)."""
        if self.is_fitted:
            header, arrays = self.to_arrays()
            return {"header": header, "arrays": arrays}
        header = {"config": self.config.to_dict(), "seed_entropy": str(self.seed_entropy)}
        return {"header": header, "arrays": None}

    def __setstate__(self, state: dict[str, Any]) -> None:
        header, arrays = state["header"], state["arrays"]
        if arrays is None:
            twin = type(self)(SOMConfig.from_dict(header["config"]))
            twin.seed_entropy = int(header["seed_entropy"])
        else:
            twin = type(self).from_arrays(header, arrays, source="pickle")
        self.__dict__.update(twin.__dict__)

    def __copy__(self) -> Self:
        """A full copy: a shallow one would share the weights while ``t_`` diverges."""
        return copy.deepcopy(self)
