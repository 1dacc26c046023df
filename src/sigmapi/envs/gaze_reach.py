"""GazeReach: a body with a movable eye that must bring an object into its grasp region.

The world (docs/algorithm.md): an object lies at body-centred position ``z`` in ``[0, 1]^d``; the
eye looks in direction ``y`` in ``[0, 1]^d``; the retina sees the object at ``x = 2 z - y``
(the relation ``z = (x + y) / 2`` of the paper's simulator). The agent sees only population
codes of ``x`` (retina) and ``y`` (gaze); ``z`` is in ``info`` for analysis, never in the
observation.

Dynamics of one step
--------------------
1. The body moves: action ``a`` shifts ``z`` by ``step_size`` along one axis (or stays, action
   0, which keeps ``z``: the body is still, so the next view shows the same ``z``).
2. Outcome, in this order: ``z`` inside the goal box (``|z - goal|_inf <= goal_radius``:
   "straight ahead within grasp range") -> reward ``reward_reach`` (+1), terminated;
   ``z`` outside ``[0, 1]^d`` -> reward ``reward_fail`` (-0.3), terminated: the object left
   the workspace, which is also the eye's whole field of view (no gaze direction ``y`` in
   ``[0, 1]^d`` puts it on the retina). Otherwise reward 0. These are the authors' docking
   values (+1 at the target, -0.3 at the borders, random restart after either).
3. The eye: with probability ``saccade_rate`` it makes a saccade to a new fixation ``y`` drawn
   uniformly among the directions that keep the object on the retina (``x`` in ``[0, 1]^d``).
   A move that pushes the object off the retina at the current fixation forces such a
   saccade (a corrective saccade), so a live object is always seen.

The time limit is not the world's own: ``gymnasium.make(ENV_ID)`` wraps the environment in
Gymnasium's ``TimeLimit`` with the ``max_episode_steps`` registered by ``import sigmapi``
(``truncated`` once that many steps passed), and code that builds the class directly wraps it
itself (:meth:`GazeReachConfig.make_env`). :class:`GazeReachConfig` holds the defaults of the
world and of its time limit, once, for ``gymnasium.make``, the class and ``sigmapi reach``.

Actions: ``0`` stay, then ``+`` and ``-`` along each axis (``1 + 2 * axis + (0 for +, 1 for
-)``): 3 actions in 1-D, 5 in 2-D; ``diagonal=True`` adds the four diagonal moves in 2-D (9
actions, each diagonal moving ``step_size`` along both axes).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from typing import Any, ClassVar, SupportsFloat, TypedDict

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.wrappers import TimeLimit
from numpy.typing import NDArray

from sigmapi import _memory, _validate
from sigmapi.codes import _WIDTH_FIX, MIN_WIDTH, PopulationCode
from sigmapi.envs.checks import check_action, check_options, check_vector
from sigmapi.envs.gaze_render import draw_workspace
from sigmapi.envs.protocols import Obs, Views, view_space
from sigmapi.errors import ConfigError

__all__ = ["ENV_ID", "GazeReachConfig", "GazeReachEnv", "move_table"]

ENV_ID = "sigmapi/GazeReach-v0"
"""The environment's Gymnasium id (registered by ``import sigmapi``, with its time limit)."""


def move_table(dim: int, diagonal: bool = False) -> NDArray[np.float64]:
    """Displacement per action in steps, ``(n_actions, dim)``; row 0 is "stay"."""
    rows = [np.zeros(dim)]
    for axis in range(dim):
        for sign in (1.0, -1.0):
            m = np.zeros(dim)
            m[axis] = sign
            rows.append(m)
    if diagonal:
        rows += [np.array(s, dtype=np.float64) for s in itertools.product((1.0, -1.0), repeat=dim)]
    return np.array(rows, dtype=np.float64)


def _unit_vector(value: object, dim: int) -> NDArray[np.float64] | None:
    """``value`` as a float vector of length ``dim`` in [0, 1] (a scalar is repeated), or None."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        return None
    if arr.ndim > 1 or arr.size not in (1, dim):
        return None
    v = np.broadcast_to(arr.ravel(), (dim,)).copy()
    if not np.all(np.isfinite(v)) or np.any(v < 0.0) or np.any(v > 1.0):
        return None
    return v


def _registered_time_limit() -> int:
    """The ``max_episode_steps`` that ``import sigmapi`` registers for :data:`ENV_ID` (the one
    place it is written; ``import sigmapi`` always runs before this module)."""
    steps = gym.spec(ENV_ID).max_episode_steps
    if steps is None:  # pragma: no cover - the registration gives one
        raise RuntimeError(f"{ENV_ID} is registered without max_episode_steps")
    return int(steps)


def _check_world(
    dim: object,
    grid: object,
    code_width: object,
    step_size: object,
    goal: object,
    goal_radius: object,
    saccade_rate: object,
) -> tuple[int, int, float, float, NDArray[np.float64], float, float]:
    """The world's parameters in their canonical types, or a ConfigError naming the first bad
    one (the checks of :class:`GazeReachConfig` and :class:`GazeReachEnv`, written once)."""
    if not _validate.is_int(dim) or dim not in (1, 2):
        raise _validate.fail("dim", "1 or 2", dim, "the task has 1-D and 2-D variants")
    d = int(dim)
    n_grid = _validate.integer("grid", grid, 2, fix="use e.g. grid=15 (the paper's 2-D network)")
    n = n_grid**d  # the code's (n, n) float64 table of hills, and one copy of it
    _memory.check(
        16 * n * n,
        f"a world of grid={n_grid}, dim={d} ({n:,} units a view)",
        "use a smaller grid (the paper's 2-D network: grid=15)",
    )
    width = _validate.width("code_width", code_width, MIN_WIDTH, fix=_WIDTH_FIX)
    step = _validate.number("step_size", step_size, 0.0, 0.5, lo_open=True, fix="use e.g. 0.05")
    g = _unit_vector(goal, d)
    if g is None:
        raise ConfigError(
            f"goal must be a number or {d} numbers in [0, 1], got {goal!r}; "
            "the default 0.5 is straight ahead"
        )
    radius = _validate.number(
        "goal_radius", goal_radius, 0.0, 0.5, lo_open=True, fix="use e.g. 0.1"
    )
    free = 1.0 - float(np.prod(np.minimum(g + radius, 1.0) - np.maximum(g - radius, 0)))
    if free < 0.05:
        raise _validate.fail(
            "goal_radius",
            "small enough to leave 5 % of the workspace outside the goal box",
            radius,
            f"the box covers {100 * (1 - free):.0f} %; use e.g. 0.1",
        )
    rate = _validate.number("saccade_rate", saccade_rate, 0.0, 1.0, fix="a probability per step")
    return d, n_grid, width, step, g, radius, rate


class WorldKwargs(TypedDict):
    """The keyword arguments of :class:`GazeReachEnv` a :class:`GazeReachConfig` sets."""

    dim: int
    grid: int
    code_width: float
    step_size: float
    goal_radius: float
    saccade_rate: float


@dataclass(frozen=True)
class GazeReachConfig:
    """The gaze-and-reach world and its time limit: the defaults of ``gymnasium.make(ENV_ID)``,
    of :class:`GazeReachEnv` and of ``sigmapi reach`` (the goal lies straight ahead, at 0.5)."""

    dim: int = field(
        default=2, metadata=_validate.bounded("int", 1, 2, fix="the task has 1-D and 2-D variants")
    )
    """1 or 2: dimensions of the task."""
    grid: int = field(default=15, metadata=_validate.bounded("int", 2, 1024, fix="e.g. 15"))
    """Units per axis of the retina and gaze codes (15x15 in 2-D, the paper's Fig. 8 network)."""
    code_width: float = field(
        default=1.0, metadata=_validate.bounded("width", MIN_WIDTH, fix=_WIDTH_FIX)
    )
    """Width of the input hills in grid units (1.0: the paper-2d preset; the 1-D paper: 0.5)."""
    step_size: float = field(
        default=0.05,
        metadata=_validate.bounded("number", 0, 0.5, lo_open=True, fix="use e.g. 0.05"),
    )
    """How far one move shifts z along an axis."""
    goal_radius: float = field(
        default=0.1, metadata=_validate.bounded("number", 0, 0.5, lo_open=True, fix="use e.g. 0.1")
    )
    """Half-width of the goal box around z = 0.5 (straight ahead, within grasp range)."""
    saccade_rate: float = field(
        default=1.0, metadata=_validate.bounded("number", 0, 1, fix="a probability per step")
    )
    """Probability of a saccade per step (1: on every step, the hardest case)."""
    max_episode_steps: int = field(
        default=_registered_time_limit(),
        metadata=_validate.bounded("int", 1, 100_000, fix="e.g. 50"),
    )
    """Time limit per episode (Gymnasium's TimeLimit; the default is the registered one, 3x
    the longest shortest path in 2-D)."""

    def __post_init__(self) -> None:
        dim, grid, width, step, _, radius, rate = _check_world(
            self.dim,
            self.grid,
            self.code_width,
            self.step_size,
            0.5,
            self.goal_radius,
            self.saccade_rate,
        )
        for name, value in (
            ("dim", dim),
            ("grid", grid),
            ("code_width", width),
            ("step_size", step),
            ("goal_radius", radius),
            ("saccade_rate", rate),
        ):
            object.__setattr__(self, name, value)
        _validate.check_fields(self)  # the bounds declared beside the fields (--help's)

    def env_kwargs(self) -> WorldKwargs:
        """Keyword arguments of :class:`GazeReachEnv` (also of ``gymnasium.make``)."""
        return {
            "dim": self.dim,
            "grid": self.grid,
            "code_width": self.code_width,
            "step_size": self.step_size,
            "goal_radius": self.goal_radius,
            "saccade_rate": self.saccade_rate,
        }

    def make_env(self, render_mode: str | None = None) -> TimeLimit[Obs, np.int64]:
        """The environment under its time limit, as ``gymnasium.make`` builds it (without
        Gymnasium's checking wrappers)."""
        env = GazeReachEnv(**self.env_kwargs(), render_mode=render_mode)
        return TimeLimit(env, max_episode_steps=self.max_episode_steps)


class GazeReachEnv(gym.Env[Obs, np.int64]):
    """Gaze-and-reach task: move the body until the seen object lies in the grasp region.

    Defaults are those of :class:`GazeReachConfig`. The environment never truncates an episode
    itself: its time limit is Gymnasium's ``TimeLimit`` (``gymnasium.make`` adds it). It is a
    view source (:class:`~sigmapi.envs.PlacedViewSource`: :attr:`x_code`, :attr:`y_code`,
    :meth:`sample_views`, :meth:`views_of`), so a map can learn from its saccades.

    Parameters
    ----------
    dim : int
        1 or 2: dimensions of ``x``, ``y`` and ``z``.
    grid : int
        Units per axis of the retina and gaze codes (the code of a 2-D position has
        ``grid**2`` units); must match the map's ``x_shape`` / ``y_shape`` when a trained
        map reads the observations.
    code_width : float
        Width of the Gaussian hills in grid units.
    step_size : float
        How far one move shifts ``z`` along an axis, as a fraction of the workspace.
    goal : float or sequence of float
        Centre of the goal box in ``z`` (default 0.5 on every axis: straight ahead).
    goal_radius : float
        Half-width of the goal box (Chebyshev radius): the grasp range.
    saccade_rate : float
        Probability of a saccade (a new gaze direction) per step, in [0, 1]; 1 = every step.
    reward_reach, reward_fail : float
        Reward on reaching the goal (+1) and on losing the object (-0.3).
    diagonal : bool
        2-D only: add the four diagonal moves.
    render_mode : {None, "rgb_array"}
        ``"rgb_array"``: :meth:`render` returns a picture (uint8 ``(H, W, 3)``) of the
        workspace (grey), the goal box (green), the gaze direction (blue lines) and the
        object (red).

    Notes
    -----
    Observations are ``{"retina": code of x, "gaze": code of y}``, float32 vectors of
    ``grid**dim`` values in [0, 1] (L2-normalised Gaussian hills, C order over the grid).
    ``info`` holds ``z``, ``x``, ``y`` (float64 positions), ``saccade`` (the eye moved this
    step), ``event`` (``"reached"``, ``"left_view"`` or ``""``) and ``is_success``.

    ``reset(options={"z": ..., "y": ...})`` places the object and the gaze by hand (tests,
    demonstrations); ``y`` must keep the object on the retina.

    Examples
    --------
    >>> env = GazeReachEnv(dim=1, grid=9)
    >>> obs, info = env.reset(seed=0)
    >>> obs["retina"].shape, int(env.action_space.n)
    ((9,), 3)
    >>> obs, r, terminated, truncated, info = env.step(0)
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 10}  # noqa: RUF012
    reset_options: ClassVar[tuple[str, ...]] = ("z", "y")
    """The names ``reset(options=...)`` takes."""

    def __init__(
        self,
        dim: int = GazeReachConfig.dim,
        grid: int = GazeReachConfig.grid,
        code_width: float = GazeReachConfig.code_width,
        step_size: float = GazeReachConfig.step_size,
        goal: float | tuple[float, ...] = 0.5,
        goal_radius: float = GazeReachConfig.goal_radius,
        saccade_rate: float = GazeReachConfig.saccade_rate,
        reward_reach: float = 1.0,
        reward_fail: float = -0.3,
        diagonal: bool = False,
        render_mode: str | None = None,
    ) -> None:
        (
            self.dim,
            self.grid,
            self.code_width,
            self.step_size,
            self.goal,
            self.goal_radius,
            self.saccade_rate,
        ) = _check_world(dim, grid, code_width, step_size, goal, goal_radius, saccade_rate)
        self.render_mode = _validate.choice(
            "render_mode", render_mode, (None, *self.metadata["render_modes"])
        )
        self.reward_reach = _validate.number("reward_reach", reward_reach, fix="e.g. 1.0")
        self.reward_fail = _validate.number("reward_fail", reward_fail, fix="e.g. -0.3")
        self.diagonal = _validate.boolean("diagonal", diagonal)
        if diagonal and self.dim != 2:
            raise _validate.fail("diagonal", "False for dim=1", diagonal, "diagonal moves are 2-D")
        self.moves = move_table(self.dim, diagonal) * self.step_size

        self.code = PopulationCode((self.grid,) * self.dim, width=self.code_width)
        n = self.code.size
        self.observation_space = view_space(n, n)
        self.action_space = spaces.Discrete(len(self.moves))
        self._z = np.full(self.dim, 0.5)
        self._y = np.full(self.dim, 0.5)
        self._done = True  # no episode yet: step() needs reset()

    # ------------------------------------------------------------------ helpers
    def in_goal(self, z: NDArray[np.float64]) -> bool:
        """Whether ``z`` lies in the goal box (closed, Chebyshev radius ``goal_radius``)."""
        return bool(np.max(np.abs(z - self.goal)) <= self.goal_radius + 1e-12)

    @staticmethod
    def in_view(z: NDArray[np.float64]) -> bool:
        """Whether ``z`` is inside the workspace ``[0, 1]^d`` (some gaze sees it)."""
        return bool(np.all(z >= 0.0) and np.all(z <= 1.0))

    @staticmethod
    def gaze_range(z: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The gaze directions that keep ``z`` on the retina: ``y`` in ``[lo, hi]`` per axis."""
        return np.maximum(2.0 * z - 1.0, 0.0), np.minimum(2.0 * z, 1.0)

    def _saccade(self) -> None:
        self._y = self.saccade_targets(np.clip(self._z, 0.0, 1.0)[None, :], self.np_random)[0]

    def saccade_targets(
        self, z: NDArray[np.float64], rng: np.random.Generator
    ) -> NDArray[np.float64]:
        """Fixations after a saccade, uniform among those that keep ``z`` on the retina.

        ``z`` ``(B, dim)`` in the workspace; returns ``y`` ``(B, dim)`` (one draw of ``B * dim``
        uniforms from ``rng``, as a step's saccade draws ``dim``).
        """
        lo, hi = self.gaze_range(z)
        return lo + (hi - lo) * rng.random(z.shape)

    # ------------------------------------------------------------------ view source
    @property
    def x_code(self) -> PopulationCode:
        """The code of the retinal position ``x`` (the ``"retina"`` observation)."""
        return self.code

    @property
    def y_code(self) -> PopulationCode:
        """The code of the gaze ``y`` (the ``"gaze"`` observation)."""
        return self.code

    @property
    def z_dim(self) -> int:
        """Dimensions of the body-centred position ``z`` (``info["z"]``)."""
        return self.dim

    def views_of(
        self, z: NDArray[np.float64], rng: np.random.Generator
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """One view of each ``z`` ``(B, dim)`` after a saccade (:meth:`saccade_targets`): the
        retina and gaze codes as the observation holds them (float32 values), as float64."""
        x, y = self._codes(z, self.saccade_targets(z, rng))
        return x.astype(np.float64), y.astype(np.float64)

    def sample_views(self, n: int, rng: np.random.Generator) -> Views:
        """``n`` pairs of views of one ``z`` each: the body keeps still, the eye looks around.

        Per pair the object lies anywhere in the workspace (uniform ``z``, the goal region
        included: the map must know the goal's ``z`` too) and the eye makes two saccades
        (:meth:`views_of`). Computed for all pairs at once rather than by stepping: an episode
        ends as soon as ``z`` is in the goal box, so stepping could never show a goal ``z``
        twice. ``rng`` draws ``z``, then view 0's fixations, then view 1's.
        """
        n = _validate.integer("n", n, 1, fix="e.g. n=20000")
        if self.saccade_rate == 0.0:
            raise ConfigError(
                "saccade_rate must be > 0 to collect views: a still eye never shows a second view"
            )
        z = rng.random((n, self.dim))
        x0, y0 = self.views_of(z, rng)
        x1, y1 = self.views_of(z, rng)
        return x0, y0, x1, y1

    def _codes(
        self, z: NDArray[np.float64], y: NDArray[np.float64]
    ) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
        """What the agent sees of objects at ``z`` with gaze ``y`` (both ``(B, dim)``): the
        retina and gaze codes, float32 ``(B, grid**dim)`` each (the observation's values)."""
        x = np.clip(2.0 * z - y, 0.0, 1.0)
        both = self.code.encode(np.concatenate([x, y])).astype(np.float32)  # one call: row by row
        return both[: len(x)], both[len(x) :]

    def _obs(self) -> Obs:
        retina, gaze = self._codes(self._z[None, :], self._y[None, :])
        return {"retina": retina[0], "gaze": gaze[0]}

    def _info(self, saccade: bool, event: str) -> dict[str, object]:
        return {
            "z": self._z.copy(),
            "x": 2.0 * self._z - self._y,
            "y": self._y.copy(),
            "saccade": saccade,
            "event": event,
            "is_success": event == "reached",
        }

    # ------------------------------------------------------------------ Gymnasium API
    def reset(
        self, *, seed: int | None = None, options: dict[str, object] | None = None
    ) -> tuple[Obs, dict[str, object]]:
        super().reset(seed=seed)
        options = check_options(options, self.reset_options, "GazeReach")
        if "z" in options:
            z = self._position(options["z"], "options['z']")
        else:
            z = self.np_random.random(self.dim)
            while self.in_goal(z):
                z = self.np_random.random(self.dim)
        self._z = z
        if "y" in options:
            y = self._position(options["y"], "options['y']")
            lo, hi = self.gaze_range(z)
            if np.any(y < lo - 1e-12) or np.any(y > hi + 1e-12):
                raise ConfigError(
                    f"options['y'] = {y.tolist()} puts the object off the retina (x = 2 z - y "
                    f"outside [0, 1]); choose y in [{lo.tolist()}, {hi.tolist()}] "
                    f"for z = {z.tolist()}"
                )
            self._y = y
        else:
            self._saccade()
        self._done = False
        return self._obs(), self._info(True, "")

    def _position(self, value: object, name: str) -> NDArray[np.float64]:
        if _validate.is_int(value) or isinstance(value, (float, np.floating)):
            value = [value] * self.dim  # one number for every axis
        return check_vector(name, value, (self.dim,), 0.0, 1.0, fix="positions in [0, 1]")

    def step(self, action: object) -> tuple[Obs, SupportsFloat, bool, bool, dict[str, object]]:
        if self._done:
            raise gym.error.ResetNeeded(
                "the episode has ended (terminated) or not begun; call reset() before step()"
            )
        a = check_action(self.action_space, action, fix="see env.moves")
        self._z = self._z + self.moves[a]
        reward = 0.0
        event = ""
        if self.in_goal(self._z):
            reward, event = self.reward_reach, "reached"
        elif not self.in_view(self._z):
            reward, event = self.reward_fail, "left_view"
        terminated = event != ""
        self._done = terminated
        # the eye: one uniform draw per step whatever happens, so rollouts stay in lockstep
        u = self.np_random.random()
        saccade = False
        if not terminated:
            x = 2.0 * self._z - self._y
            if u < self.saccade_rate or np.any(x < 0.0) or np.any(x > 1.0):
                self._saccade()
                saccade = True
        return self._obs(), reward, terminated, False, self._info(saccade, event)

    def render(self) -> NDArray[np.uint8] | None:
        """A picture of the workspace ``[0, 1]^d`` (``render_mode="rgb_array"``), else None.

        Grey: the workspace; green: the goal box; blue: the gaze direction ``y``; red: the
        object ``z`` (outside the grey square once it has left the view). 1-D tasks are drawn
        as a strip.
        """
        if self.render_mode != "rgb_array":
            return None
        return draw_workspace(self.goal, self.goal_radius, self._y, self._z)
