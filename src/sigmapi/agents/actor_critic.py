"""Actor-critic over linear features, with the authors' parameters as defaults.

The critic estimates ``V(s) = v . phi(s)``; the actor holds one preference vector per action,
``p_a(s) = W_a . phi(s)``, and chooses by a softmax with inverse temperature ``beta``:
``pi(a | s) = exp(beta p_a) / sum_b exp(beta p_b)``. After each step, with the TD error

    delta = r + gamma V(s') - V(s)        (V(s') = 0 after termination, not after truncation)

both learn: ``v += critic_lr delta phi(s)`` and ``W_a += actor_lr delta phi(s)`` for the action
taken (the actor-critic of Barto, Sutton & Anderson 1983 as used in the authors' docking
model: discount 0.9, rates 0.1, inverse temperature 2; docs/algorithm.md).

References
----------
C. Weber, S. Wermter and A. Zochios, "Robot docking with neural vision and reinforcement",
Knowledge-Based Systems 17 (2004) 165-172. R. S. Sutton and A. G. Barto, Reinforcement
Learning: An Introduction (1998), section 6.6.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi import _validate

__all__ = ["ActorCritic", "ActorCriticConfig"]


@dataclass(frozen=True)
class ActorCriticConfig:
    """The learner's settings, the defaults of :class:`ActorCritic` (the authors' docking
    model)."""

    gamma: float = field(
        default=0.9, metadata=_validate.bounded("number", 0, 1, fix="the authors use 0.9")
    )
    """Discount of the actor-critic (the authors: 0.9)."""
    critic_lr: float = field(
        default=0.1, metadata=_validate.bounded("number", 0, 10, fix="the authors use 0.1")
    )
    """Learning rate of the critic (the authors: 0.1), per unit of ``|phi|^2``."""
    actor_lr: float = field(
        default=0.1, metadata=_validate.bounded("number", 0, 10, fix="the authors use 0.1")
    )
    """Learning rate of the actor (the authors: 0.1), per unit of ``|phi|^2``."""
    beta: float = field(
        default=2.0, metadata=_validate.bounded("number", 0, 1e6, fix="the authors use 2")
    )
    """Inverse temperature of the softmax policy (the authors: 2)."""

    def __post_init__(self) -> None:
        _validate.check_fields(self)  # the bounds declared beside the fields


class ActorCritic:
    """Linear actor-critic with a softmax policy.

    Parameters
    ----------
    n_features : int
        Length of the feature vector ``phi(s)``.
    n_actions : int
        Number of discrete actions.
    gamma : float
        Discount.
    critic_lr, actor_lr : float
        Learning rates of the critic and the actor, per unit of ``|phi|^2``: the wrappers
        give features of L2 length 1.
    beta : float
        Inverse temperature of the softmax.

    seed : int or numpy.random.Generator, optional
        Source of the action choices.

    Notes
    -----
    Defaults are :class:`ActorCriticConfig`'s (the authors' values), and so are the checks.

    Examples
    --------
    >>> ac = ActorCritic(n_features=3, n_actions=2, seed=0)
    >>> phi = np.array([1.0, 0.0, 0.0])
    >>> delta = ac.update(phi, ac.act(phi), 1.0, phi, terminated=True)
    >>> float(delta), float(ac.value(phi))
    (1.0, 0.1)
    """

    def __init__(
        self,
        n_features: int,
        n_actions: int,
        gamma: float = ActorCriticConfig.gamma,
        critic_lr: float = ActorCriticConfig.critic_lr,
        actor_lr: float = ActorCriticConfig.actor_lr,
        beta: float = ActorCriticConfig.beta,
        seed: int | np.random.Generator | None = None,
    ) -> None:
        self.n_features = _validate.integer("n_features", n_features, 1)
        self.n_actions = _validate.integer("n_actions", n_actions, 1)
        self.config = ActorCriticConfig(gamma, critic_lr, actor_lr, beta)  # checks them
        self.gamma, self.critic_lr = self.config.gamma, self.config.critic_lr
        self.actor_lr, self.beta = self.config.actor_lr, self.config.beta
        self.rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
        self.v_ = np.zeros(self.n_features)
        self.w_ = np.zeros((self.n_actions, self.n_features))

    @classmethod
    def from_config(
        cls,
        config: ActorCriticConfig,
        n_features: int,
        n_actions: int,
        seed: int | np.random.Generator | None = None,
    ) -> ActorCritic:
        """A learner with ``config``'s settings for ``n_features`` features and ``n_actions``."""
        return cls(
            n_features,
            n_actions,
            config.gamma,
            config.critic_lr,
            config.actor_lr,
            config.beta,
            seed=seed,
        )

    def _phi(self, phi: ArrayLike) -> NDArray[np.float64]:
        arr = np.asarray(phi, dtype=np.float64).ravel()
        if arr.shape != (self.n_features,):
            raise ValueError(f"phi must have {self.n_features} features, got shape {np.shape(phi)}")
        return arr

    def value(self, phi: ArrayLike) -> float:
        """Critic's value ``V(s) = v . phi(s)``."""
        return float(self.v_ @ self._phi(phi))

    def values(self, phis: ArrayLike) -> NDArray[np.float64]:
        """Values of many states, ``(B, n_features)`` -> ``(B,)``."""
        return np.asarray(phis, dtype=np.float64) @ self.v_

    def policy(self, phi: ArrayLike) -> NDArray[np.float64]:
        """Action probabilities ``softmax(beta W phi)``; ``(n_actions,)``."""
        p = self.beta * (self.w_ @ self._phi(phi))
        p = np.exp(p - p.max())
        return p / p.sum()

    def act(self, phi: ArrayLike) -> int:
        """Draw an action from the softmax policy."""
        p = self.policy(phi)
        return int(
            min(np.searchsorted(np.cumsum(p), self.rng.random() * p.sum()), self.n_actions - 1)
        )

    def update(
        self, phi: ArrayLike, action: int, reward: float, phi_next: ArrayLike, terminated: bool
    ) -> float:
        """One TD step from ``(s, a, r, s')``; returns the TD error ``delta``.

        ``terminated``: ``s'`` is terminal (its value is 0). On truncation pass False: the
        time limit is not part of the task, so ``V(s')`` is bootstrapped.
        """
        f = self._phi(phi)
        v_next = 0.0 if terminated else float(self.v_ @ self._phi(phi_next))
        delta = float(reward) + self.gamma * v_next - float(self.v_ @ f)
        self.v_ += self.critic_lr * delta * f
        self.w_[int(action)] += self.actor_lr * delta * f
        return delta
