"""RobotDock: the robot moves its base until the ball lies within its arm's reach, then grasps.

The authors' docking task (Weber, Wermter & Zochios 2004) on the simulated body: the base
moves by discrete actions while the head keeps looking around, and the learner sees only the
head camera's retina code and the neck's gaze code (``{"retina", "gaze"}``), never ``z``.

Dynamics of one step
--------------------
1. The base moves (kinematically, its actuators' targets set to the new pose): action 0 one
   ``step_length`` forward, 1 backward, 2 turn left by ``turn``, 3 turn right.
2. Outcome, in this order: the ball's body-centred position ``z`` inside the goal box (the
   grasp region: ``|z - goal|_inf <= goal_radius`` in workspace units) -> docked, reward
   ``reward_reach`` (+1), terminated; the arm then reaches for the ball where the head sees it
   (:func:`~sigmapi.envs.robot.reach.scripted_reach`, in the physics), and ``info["is_success"]``
   is whether the hand touched it. ``z`` outside the workspace ``[0, 1]^2``, or the base or
   torso touching the table -> reward ``reward_fail`` (-0.3), terminated. Otherwise 0.
3. The head: with probability ``saccade_rate`` it makes a saccade to a neck pose, uniform
   among those that keep the ball in view; when a move has pushed the ball out of view it
   must make one.

The time limit is set at registration (``gymnasium.make("sigmapi/RobotDock-v0")``:
``max_episode_steps=100``), not here.

The environment is a :class:`~sigmapi.envs.PlacedViewSource` too (:attr:`~RobotDockEnv.x_code`,
:attr:`~RobotDockEnv.y_code`, ``sample_views``, ``views_of``; through a
:class:`~sigmapi.envs.robot.RobotViews` of its codes on a scene of its own, so recording views
leaves the episode as it is): :func:`~sigmapi.envs.learn_map_in_env` learns a map in it, and
the wrappers of :mod:`sigmapi.envs.wrappers` check a map's codes against it.
"""

from __future__ import annotations

from typing import Any, ClassVar, SupportsFloat

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.envs.checks import check_action, check_options
from sigmapi.envs.protocols import Obs, Views, view_space
from sigmapi.envs.robot.frames import RETINA_SOURCES, Frames, FramesCodes, Workspace
from sigmapi.envs.robot.reach import perceived_target, scripted_reach
from sigmapi.envs.robot.scene import OBJECT_RADIUS, TABLE_HEIGHT, Pose, Scene
from sigmapi.envs.robot.views import RobotViews
from sigmapi.errors import ConfigError

__all__ = ["ACTIONS", "BALL_BEYOND_EDGE", "ENV_ID", "RobotDockEnv"]

ENV_ID = "sigmapi/RobotDock-v0"
"""The environment's Gymnasium id (registered by ``import sigmapi``, with its time limit)."""

ACTIONS = ("forward", "backward", "turn_left", "turn_right")
"""The base's moves, by action index (the authors' docking robot's four)."""

_TABLE_EDGE = 0.15  # world x of the table's near edge (robot.xml)
BALL_BEYOND_EDGE = (0.05, 0.22)
"""How far beyond the table's near edge the ball lies at the start (metres, uniform): close
enough that every base pose of the grasp region that faces the table (within 0.25 rad) clears
the edge with the torso's box and the base's disc, so that every episode can dock; a ball
further in is in the grasp region only from poses that touch the table."""


class RobotDockEnv(FramesCodes, gym.Env[Obs, np.int64]):
    """Dock the simulated robot at the table so that its arm can reach the ball.

    Parameters
    ----------
    grid : int
        Units per axis of the retina and gaze codes (``grid**2`` values each).
    code_width : float
        Width of the codes' hills, grid units.
    retina : {"projection", "pixels"}
        Retinal position from the camera's exact projection, or from the rendered head
        camera's pixels (slower).
    step_length : float
        Metres per forward or backward move.
    turn : float
        Radians per turn.
    goal : tuple of float
        Centre of the grasp region in workspace units (default: straight ahead, 0.45 m from
        the neck point).
    goal_radius : float
        Half-width of the grasp region (Chebyshev, workspace units).
    saccade_rate : float
        Probability of a saccade per step.
    reach : bool
        Run the scripted reach after docking (False: ``is_success`` is docking alone).
    reward_reach, reward_fail : float
        Reward on docking (+1) and on losing the ball or bumping the table (-0.3).
    render_mode : {None, "rgb_array"}
        ``"rgb_array"``: :meth:`render` returns the third-person view beside the head
        camera's view.

    Observations: ``{"retina": code of x, "gaze": code of y}``, float32 vectors of
    ``grid**2`` values in [0, 1]. ``info``: ``z`` (workspace position, for analysis only),
    ``direction`` (radians), ``x``, ``y`` (positions in [0, 1]^2), ``event`` (``"docked"``,
    ``"lost"``, ``"bumped"`` or ``""``), ``docked``, ``touched`` and ``is_success``.

    Examples
    --------
    >>> env = RobotDockEnv(grid=6)
    >>> obs, info = env.reset(seed=0)
    >>> obs["retina"].shape, int(env.action_space.n)
    ((36,), 4)
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 8}  # noqa: RUF012
    reset_options: ClassVar[tuple[str, ...]] = ()
    """The names ``reset(options=...)`` takes: none."""

    def __init__(
        self,
        grid: int = 12,
        code_width: float = 1.0,
        retina: str = "projection",
        step_length: float = 0.035,
        turn: float = float(np.deg2rad(4.5)),
        goal: tuple[float, float] | None = None,
        goal_radius: float = 0.1,
        saccade_rate: float = 1.0,
        reach: bool = True,
        reward_reach: float = 1.0,
        reward_fail: float = -0.3,
        render_mode: str | None = None,
    ) -> None:
        self.retina = _validate.choice("retina", retina, RETINA_SOURCES)
        self.step_length = _validate.number("step_length", step_length, 0.0, 0.2, lo_open=True)
        self.turn = _validate.number("turn", turn, 0.0, 0.5, lo_open=True, fix="radians")
        self.goal_radius = _validate.number("goal_radius", goal_radius, 0.0, 0.4, lo_open=True)
        self.saccade_rate = _validate.number("saccade_rate", saccade_rate, 0.0, 1.0)
        self.reach = _validate.boolean("reach", reach)
        self.reward_reach = _validate.number("reward_reach", reward_reach)
        self.reward_fail = _validate.number("reward_fail", reward_fail)
        self.render_mode = _validate.choice(
            "render_mode", render_mode, (None, *self.metadata["render_modes"])
        )
        self.scene = Scene()
        self.frames = Frames(self.scene, grid, code_width, workspace=Workspace())
        given = goal is not None
        if goal is None:  # straight ahead, 0.45 m from the neck point
            el = -np.arctan2(self.frames.drop, 0.45)
            e0, e1 = self.frames.elevation
            goal = (0.5, float((el - e0) / (e1 - e0)))
        lo, hi = self.goal_radius, 1.0 - self.goal_radius
        if isinstance(goal, (str, bytes)) or not hasattr(goal, "__len__") or len(goal) != 2:
            raise _validate.fail("goal", "2 numbers (x, y) in [0, 1]^2", goal, "e.g. (0.5, 0.4)")
        fix = (
            f"with goal_radius={self.goal_radius:g} the goal box must lie inside [0, 1]^2: "
            f"each number in [{lo:.3g}, {hi:.3g}]"
        )
        pair = tuple(_validate.number("goal", g, lo, hi, fix=fix) if given else g for g in goal)
        if not given and not all(lo <= g <= hi for g in pair):
            raise _validate.fail(
                "goal_radius",
                "small enough for the default goal's box to lie "
                f"inside [0, 1]^2 (the default goal is {pair[0]:.3g}, "
                f"{pair[1]:.3g})",
                self.goal_radius,
                "give a smaller goal_radius, or a goal of your own",
            )
        self.goal = np.asarray(pair, dtype=np.float64)
        n = self.frames.code.size
        self.observation_space = view_space(n, n)
        self.action_space = spaces.Discrete(len(ACTIONS))
        self._views: RobotViews | None = None
        self._base = np.zeros(3)
        self._seen: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
        self._uv = np.zeros(2)
        self._done = True

    @property
    def grid(self) -> int:
        """Units per axis of the codes."""
        return self.frames.grid

    # ------------------------------------------------------------------ view source
    @property
    def view_source(self) -> RobotViews:
        """The saccade views of this robot's codes (built on first use, on its own scene)."""
        if self._views is None:
            self._views = RobotViews(
                self.grid, self.frames.code.width, retina=self.retina, margin=self.frames.margin
            )
        return self._views

    def sample_views(self, n: int, rng: np.random.Generator) -> Views:
        """``n`` view pairs of the still robot (:meth:`RobotViews.sample_views`)."""
        return self.view_source.sample_views(n, rng)

    def views_of(
        self, z: NDArray[np.float64], rng: np.random.Generator
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """One view of each workspace position ``z`` ``(B, 2)`` (:meth:`RobotViews.views_of`)."""
        return self.view_source.views_of(z, rng)

    # ------------------------------------------------------------------ helpers
    def z(self) -> NDArray[np.float64]:
        """The ball's body-centred position now, workspace units ``(2,)`` (analysis only)."""
        return self.frames.z(self._direction()[None, :])[0]

    def _direction(self) -> NDArray[np.float64]:
        """The ball's direction now, ``(azimuth, elevation)`` in radians."""
        return self.frames.direction(self.scene.object_position()[None, :])[0]

    def in_goal(self, z: NDArray[np.float64]) -> bool:
        """Whether ``z`` lies in the grasp region."""
        return bool(np.max(np.abs(z - self.goal)) <= self.goal_radius + 1e-12)

    def _set_base(self, base: NDArray[np.float64]) -> None:
        self._base = base
        neck = (self.scene.joint("neck_pan"), self.scene.joint("neck_tilt"))
        ball = tuple(self.scene.object_position())
        self.scene.pose(Pose(base=tuple(base), neck=neck, object=ball))

    def _look(self, saccade: bool) -> bool:
        """Read the retina at the current neck pose (after a saccade if asked or needed);
        False if no neck pose sees the ball."""
        seen = None if saccade else self._read()
        if seen is None:
            try:
                self.frames.saccade(self.np_random, max_tries=200)
            except ConfigError:
                return False
            seen = self._read()
        if seen is None:
            return False
        self._seen = seen
        return True

    def _read(self) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
        neck = np.array([self.scene.joint("neck_pan"), self.scene.joint("neck_tilt")])
        uv = self.frames.retinal_pixels(self.retina)
        if uv is None or not self.frames.in_view(uv):
            return None
        self._uv = uv
        return self.frames.retina(uv), self.frames.gaze(neck)

    def _obs(self) -> Obs:
        assert self._seen is not None
        x, y = self.frames.code.encode(np.clip(np.stack(self._seen), 0.0, 1.0)).astype(np.float32)
        return {"retina": x, "gaze": y}

    def _info(
        self, event: str, direction: NDArray[np.float64], touched: bool = False
    ) -> dict[str, object]:
        x, y = self._seen if self._seen is not None else (np.full(2, np.nan),) * 2
        return {
            "z": self.frames.z(direction[None, :])[0],
            "direction": direction,
            "x": x.copy(),
            "y": y.copy(),
            "event": event,
            "docked": event == "docked",
            "touched": touched,
            "is_success": event == "docked" and (touched or not self.reach),
        }

    # ------------------------------------------------------------------ Gymnasium API
    def reset(
        self, *, seed: int | None = None, options: dict[str, object] | None = None
    ) -> tuple[Obs, dict[str, object]]:
        """A new episode: the ball somewhere on the table near its edge, the base at a random
        pose that puts the ball in the workspace, outside the grasp region, off the table."""
        super().reset(seed=seed)
        check_options(options, self.reset_options, "RobotDock")
        rng = self.np_random
        for _ in range(1000):
            ball = np.array(
                [
                    _TABLE_EDGE + rng.uniform(*BALL_BEYOND_EDGE),
                    rng.uniform(-0.5, 0.5),
                    TABLE_HEIGHT + OBJECT_RADIUS,
                ]
            )
            z = rng.random(2)
            if self.in_goal(z):
                continue
            yaw = rng.uniform(-0.5, 0.5)
            self.scene.pose(Pose(base=(0.0, 0.0, yaw), object=tuple(ball)))
            offset = self.frames.world_position(z) - self.scene.object_position()
            base = np.array([-offset[0], -offset[1], yaw])
            self._set_base(base)
            if not self.scene.robot_touches_table() and self._look(saccade=True):
                break
        else:  # pragma: no cover - the workspace always has room
            raise RuntimeError("found no start pose in 1000 tries")
        self._done = False
        return self._obs(), self._info("", self._direction())

    def step(self, action: object) -> tuple[Obs, SupportsFloat, bool, bool, dict[str, object]]:
        if self._done:
            raise gym.error.ResetNeeded("the episode has ended or not begun; call reset()")
        a = check_action(self.action_space, action, fix=f"the moves {ACTIONS}")
        x, y, yaw = self._base
        if a < 2:
            s = self.step_length * (1.0 if a == 0 else -1.0)
            base = np.array([x + s * np.cos(yaw), y + s * np.sin(yaw), yaw])
        else:
            base = np.array([x, y, yaw + (self.turn if a == 2 else -self.turn)])
        self._set_base(base)
        d = self._direction()  # before the reach, which may push the ball
        z = self.frames.z(d[None, :])[0]
        reward, event, touched = 0.0, "", False
        u = self.np_random.random()  # one draw per step, whatever happens
        if self.scene.robot_touches_table():
            reward, event = self.reward_fail, "bumped"
        elif np.any(z < 0.0) or np.any(z > 1.0) or not self._look(u < self.saccade_rate):
            reward, event = self.reward_fail, "lost"
        elif self.in_goal(z):
            reward, event = self.reward_reach, "docked"
            if self.reach:
                touched = scripted_reach(self.scene, perceived_target(self.scene, self._uv))
        terminated = event != ""
        self._done = terminated
        return self._obs(), reward, terminated, False, self._info(event, d, touched)

    def render(self) -> NDArray[np.uint8] | None:
        """The third-person camera (240 x 320) beside the head camera (scaled to 240 x 240),
        uint8 ``(240, 560, 3)``, for ``render_mode="rgb_array"``; else None."""
        if self.render_mode != "rgb_array":
            return None
        third = self.scene.render("third")
        head = self.scene.render("head")
        k = max(1, 240 // head.shape[0])
        big = np.repeat(np.repeat(head, k, axis=0), k, axis=1)
        pad = np.zeros((240, 240, 3), dtype=np.uint8)
        pad[: big.shape[0], : big.shape[1]] = big[:240, :240]
        return np.concatenate([third, pad], axis=1).astype(np.uint8)

    def close(self) -> None:
        self.scene.close()
        if self._views is not None:
            self._views.frames.scene.close()
