"""A model as a model file's parts: its header and arrays to and from config, iteration count,
seed entropy and the kernel's state (or dense weights).

:mod:`sigmapi.io` reads and writes the archive; this module says what a model's header and
arrays hold and checks them; :class:`sigmapi.SigmaPiSOM` turns the parts into a model. It
never imports the estimator.

The header holds the resolved ``config``, the iteration count ``t``, the ``seed_entropy`` of
the random streams (a decimal string), the ``backend`` that wrote the file and, for a run
with refinement, ``refined`` (its pairs done; absent: 0) and, for one refined on given rows
(``fit(views)``, a stream) rather than the built-in task, ``refine_rows`` (the rows of a
round, which a resumed refinement must be given again). The arrays
are the backend's own (:meth:`sigmapi.kernels.base.Kernel.file_arrays`: dense ``weights``
or ``state_<name>`` arrays of its layout), stored once in the backend's precision. The
backend that wrote a file reads its state back bit for bit, so that the run continues
exactly; any other backend starts from the dense weights of the arrays (read by the writer,
or without it where it is not installed, :func:`sigmapi.kernels.file_weights`). Files of
format version 1 stored the dense weights beside a backend's state; they still load (the
kernel checks that the two agree).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.config import SOMConfig
from sigmapi.errors import ConfigError, ModelFileError, NumericalError
from sigmapi.kernels import Kernel, KernelState, file_weights, get_backend
from sigmapi.kernels.base import MAX_WEIGHT

__all__ = ["ModelParts", "read_parts", "write_parts"]

S = TypeVar("S", bound=KernelState)

_INVALID = (ValueError, KeyError, TypeError, IndexError)
"""What a kernel's reader raises on arrays that do not make its state."""


@dataclass(frozen=True)
class ModelParts:
    """What a model file holds, checked.

    Attributes
    ----------
    config : SOMConfig
        The model's config (with the backend it is loaded onto).
    t : int
        Learning iterations done.
    seed_entropy : int
        Entropy of the run's random streams.
    state : KernelState or None
        The kernel's own state, read back bit for bit (the file's writer is the backend).
    weights : ndarray of shape (n_units, n_x, n_y) or None
        Dense float64 weights for the backend to prepare (set where ``state`` is None).
    refined : int
        Refinement pairs done (header ``refined``; absent in files without refinement: 0).
    refine_rows : int or None
        Rows a refinement round runs on (header ``refine_rows``; None: the built-in task).
    """

    config: SOMConfig
    t: int
    seed_entropy: int
    state: KernelState | None = None
    weights: NDArray[np.float64] | None = None
    refined: int = 0
    refine_rows: int | None = None


def write_parts(
    config: SOMConfig,
    t: int,
    seed_entropy: int,
    kernel: Kernel[S],
    state: S,
    refined: int = 0,
    refine_rows: int | None = None,
) -> tuple[dict[str, object], dict[str, NDArray[np.generic]]]:
    """The header and arrays of a model file holding ``state``, the state of ``kernel``.

    Raises :class:`~sigmapi.errors.NumericalError` if the state holds NaN or inf or weights
    beyond :data:`~sigmapi.kernels.base.MAX_WEIGHT`, so that no file is written that
    :func:`read_parts` would refuse.
    """
    arrays: dict[str, NDArray[np.generic]] = dict(kernel.file_arrays(state))
    for k, v in arrays.items():
        if not np.all(np.isfinite(v)):
            raise NumericalError(
                f"the model's {k} hold NaN or inf values (an overflow in training, at "
                f"iteration <= {t}); it cannot be saved: retrain with codes and "
                "init_scale of about 1"
            )
    top = kernel.max_abs(state)
    if not top <= MAX_WEIGHT:  # what loading would refuse
        raise NumericalError(
            f"the model's weights reach {top:.3g}, beyond {MAX_WEIGHT:g} (an overflow in "
            "training); it cannot be saved: retrain with codes and init_scale of about 1"
        )
    header = {
        "config": config.to_dict(),
        "t": int(t),
        "seed_entropy": str(seed_entropy),
        "backend": kernel.NAME,
    }
    if config.refine_rounds > 0 or refined:  # files of runs without refinement as before
        header["refined"] = int(refined)
    if refined and refine_rows is not None:  # refined on given rows, not the built-in task
        header["refine_rows"] = int(refine_rows)
    return header, arrays


def read_parts(
    header: dict[str, Any],
    arrays: dict[str, NDArray[Any]],
    backend: str | None = None,
    source: str = "arrays",
) -> ModelParts:
    """The parts of a model file's ``header`` and ``arrays`` (:func:`write_parts`), checked.

    ``backend`` loads the model onto another kernel (which starts from the dense weights),
    also where the backend that wrote it is not installed.
    Raises :class:`~sigmapi.errors.ModelFileError`, its message starting with ``source``, if
    the header and arrays do not make a model.
    """
    name = source
    try:
        stored = header["config"]
        if backend is not None and isinstance(stored, dict):  # also from a backend not here
            stored = {**stored, "backend": backend}
        cfg = SOMConfig.from_dict(stored)
    except (ConfigError, TypeError, KeyError) as exc:
        raise ModelFileError(f"{name!r}: stored config is invalid ({exc})") from None
    shape = (
        int(np.prod(cfg.map_shape)),
        int(np.prod(cfg.x_shape)),
        int(np.prod(cfg.y_shape)),
    )
    if not arrays:
        raise ModelFileError(f"{name!r}: holds neither weights nor a backend state")
    bad = (
        f"{name!r}: weights must be floats of magnitude <= {MAX_WEIGHT:g} (found NaN, "
        "inf or an overflow such as raw x scale); the file is damaged or was edited"
    )
    kernel = get_backend(cfg.backend)
    writer = header.get("backend")
    state: KernelState | None = None
    weights: NDArray[np.float64] | None = None
    try:
        if writer == kernel.NAME:
            state = kernel.from_file_arrays(shape, arrays, tol=cfg.kernel_tol)
            top = kernel.max_abs(state)
        else:
            weights = file_weights(writer, shape, arrays)
            top = float(np.abs(weights).max(initial=0.0))
    except _INVALID as exc:
        raise ModelFileError(
            f"{name!r}: backend state is invalid ({exc}); the file is damaged or was edited"
        ) from None
    if not top <= MAX_WEIGHT:  # also NaN
        raise ModelFileError(bad)
    t = _validate.integer(f"{name!r}: iteration count", header.get("t"), 0, error=ModelFileError)
    try:
        entropy = int(header["seed_entropy"])
    except (KeyError, TypeError, ValueError):
        raise ModelFileError(f"{name!r}: seed_entropy must be an integer string") from None
    if entropy < 0:
        raise ModelFileError(f"{name!r}: seed_entropy must be >= 0, got {entropy}")
    refined = _validate.integer(
        f"{name!r}: refinement pairs done", header.get("refined", 0), 0, error=ModelFileError
    )
    rows = header.get("refine_rows")
    if rows is not None:
        rows = _validate.integer(
            f"{name!r}: refinement rows a round", rows, 1, error=ModelFileError
        )
    return ModelParts(cfg, t, entropy, state, weights, refined, rows)
