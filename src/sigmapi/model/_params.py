"""The estimator's scikit-learn glue: hyperparameters in and out, and what its checks ask.

:class:`ParamsMixin` gives :class:`sigmapi.SigmaPiSOM` scikit-learn's ``get_params`` /
``set_params`` (every field of :class:`~sigmapi.config.SOMConfig` is one hyperparameter) and
the hooks ``check_is_fitted`` and ``clone`` use. scikit-learn is imported only when one of
its own functions asks.
"""

from __future__ import annotations

from typing import Any, Self

from sigmapi.config import SOMConfig
from sigmapi.errors import ConfigError
from sigmapi.model._core import FIELDS, MapCore, entropy_of

__all__ = ["ParamsMixin"]


class ParamsMixin(MapCore):
    """scikit-learn's parameter protocol over a ``config`` (a :class:`SOMConfig`)."""

    def __sklearn_is_fitted__(self) -> bool:
        """What ``sklearn.utils.validation.check_is_fitted`` asks: whether there are weights."""
        return self.is_fitted

    def __sklearn_tags__(self) -> Any:
        """scikit-learn's tags (asked by its checks from 1.6 on): unsupervised, needs fitting."""
        from sklearn.utils import Tags, TargetTags

        return Tags(estimator_type=None, target_tags=TargetTags(required=False))

    def get_params(self, deep: bool = True) -> dict[str, object]:
        """The hyperparameters, as scikit-learn's ``get_params``: every field of the config.

        ``SigmaPiSOM(**model.get_params())`` is an unfitted model with the same
        hyperparameters (what ``sklearn.base.clone`` builds; ``extra``, the preset's notes, is
        left out). ``deep`` is there for scikit-learn's signature: nothing is nested.

        Examples
        --------
        >>> from sigmapi import SigmaPiSOM
        >>> som = SigmaPiSOM(map_shape=(6,), seed=0)
        >>> som.get_params()["map_shape"], som.set_params(iterations=2000).config.iterations
        ((6,), 2000)
        """
        return {k: getattr(self.config, k) for k in FIELDS}

    def set_params(self, **params: Any) -> Self:
        """Change hyperparameters (``config`` and/or fields of :class:`SOMConfig`); returns self.

        A fitted model keeps its weights and iteration count (so ``set_params(eps=0.001)``
        followed by :meth:`partial_fit` continues with the new value), except when a grid
        changes (``map_shape``, ``x_shape``, ``y_shape``): the weights no longer fit and are
        discarded (call :meth:`fit`). A new ``seed`` re-seeds the random streams; a new
        ``backend`` moves the weights onto that kernel.
        """
        if self._run.calling_back:
            shown = ", ".join(sorted(params)) or "nothing"
            raise ConfigError(
                f"set_params must not run inside a callback of a training call (it would "
                f"change {shown} under the run in progress, which keeps the config it started "
                "with); change parameters after fit / partial_fit returns"
            )
        cfg = params.pop("config", self.config)
        if not isinstance(cfg, SOMConfig):
            raise ConfigError(
                f"config must be a sigmapi.SOMConfig, got {type(cfg).__name__}; "
                "or pass single hyperparameters, e.g. set_params(iterations=50000)"
            )
        old, new = self.config, cfg.replace(**params) if params else cfg
        self._run.reconfigure(new)
        if new.seed != old.seed:
            self.seed_entropy = entropy_of(new.seed)
        return self

    def replay_twin(self) -> Self:
        """An unfitted model with this one's config and random streams (its seed entropy).

        ``model.replay_twin().fit(iterations=model.t_)`` replays the run that made ``model``
        (the training data of every iteration is a pure function of the seed entropy and the
        iteration number). ``sklearn.base.clone(model)`` instead builds a model from the
        hyperparameters alone: with ``seed=None``, other random streams.
        """
        twin = type(self)(self.config)
        twin.seed_entropy = self.seed_entropy
        return twin
