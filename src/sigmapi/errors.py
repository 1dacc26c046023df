"""Error classes. Each subclasses the built-in a caller would catch (as Nengo and Gymnasium do).

Every message names the parameter, the constraint, the value received and the fix.
"""

from __future__ import annotations

__all__ = ["ConfigError", "ModelFileError", "NotFittedError"]


class ConfigError(ValueError):
    """A configuration value (API argument, TOML preset, ``--set`` override) is invalid."""


class ModelFileError(ValueError):
    """A model file or checkpoint is missing, damaged, of another version, or hostile."""


class NotFittedError(RuntimeError):
    """The model has no weights yet: call ``fit`` (or ``partial_fit``) first."""
