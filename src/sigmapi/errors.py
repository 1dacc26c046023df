"""Error classes: one root, :class:`SigmapiError`, and its subclasses.

Each subclass also subclasses the built-in a caller would catch (as Nengo and Gymnasium do):
``except ValueError`` keeps working, and ``except SigmapiError`` catches everything this
package raises on purpose. Every message names the parameter, the constraint, the value
received and the fix.
"""

from __future__ import annotations

__all__ = [
    "ConfigError",
    "DataError",
    "ModelFileError",
    "NotFittedError",
    "NumericalError",
    "ResourceError",
    "SigmapiError",
    "UsageError",
    "install_hint",
]


def install_hint(extra: str) -> str:
    """How to install the optional dependencies ``extra`` (a name of pyproject.toml's
    ``[project.optional-dependencies]``), the one wording of every message and ``--help`` that
    names one: from PyPI and from a clone, as the README installs.

    Examples
    --------
    >>> install_hint("robot")
    "pip install 'sigmapi[robot]' (from a clone: pip install '.[robot]')"
    """
    return f"pip install 'sigmapi[{extra}]' (from a clone: pip install '.[{extra}]')"


class SigmapiError(Exception):
    """Root of the errors sigmapi raises on purpose (a user mistake, a bad file)."""


class ConfigError(SigmapiError, ValueError):
    """A setting is invalid: a hyperparameter, an API argument, a TOML file or preset, a
    ``key=value`` override."""


class DataError(SigmapiError, ValueError):
    """An array is unfit to use: wrong shape or dtype, NaN or inf, out of range, or arrays
    whose rows do not match (codes, views, positions)."""


class ModelFileError(SigmapiError, ValueError):
    """A model file or checkpoint is missing, damaged, of another version, or hostile."""


class NotFittedError(SigmapiError, RuntimeError, AttributeError):
    """The model has no weights yet: call ``fit`` (or ``partial_fit``) first.

    An ``AttributeError`` too, as scikit-learn's: the learned attributes (``weights_``,
    ``t_``) of an unfitted model do not exist, so ``hasattr`` and
    ``sklearn.utils.validation.check_is_fitted`` tell an unfitted model.
    """


class ResourceError(SigmapiError, MemoryError):
    """What was asked needs more memory than the machine has available (checked beforehand)."""


class NumericalError(SigmapiError, FloatingPointError):
    """A model's weights overflowed (NaN or inf): the model cannot be used or saved."""


class UsageError(SigmapiError):
    """A mistake on the command line, reported as one line with exit status 2.

    The command line's own (:mod:`sigmapi.cli`), as it names flags: library code raises
    :class:`ConfigError` for a bad setting and :class:`DataError` for a bad array.
    """
