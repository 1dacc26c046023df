"""ICubReach: the iCub sees a ball on the table from a random gaze and reaches for it.

One reach is one episode of one step. ``reset`` puts the ball at a random place of the arm's
reach (:data:`~sigmapi.envs.icub.frames.REACH_REGION`), the eyes and neck at a random gaze that
keeps it in the right eye's view and the arm at home. The observation is what the robot
measures: ``"retina"``, the ball's position in the right eye's image as a fraction of its side
(``(u, v) / eye_size``, from the exact projection or from the rendered pixels), ``"gaze"``, the
six gaze angles (radians, :data:`~sigmapi.envs.icub.scene.GAZE`) and ``"arm"``, the right arm's
seven joint angles. The action is an arm posture, each joint's range mapped onto [-1, 1]; the
step moves the arm there in the physics, approaching from above
(:func:`~sigmapi.envs.icub.reach.physical_reach`), and ends the episode: reward 1 and
``info["is_success"]`` when the hand touched the ball, else 0.

``env.unwrapped.render_eyes()`` returns both eyes' frames (the images the retina is read
from); ``render_mode="rgb_array"`` renders a third-person view.
"""

from __future__ import annotations

from typing import Any, ClassVar, SupportsFloat

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from sigmapi.envs.checks import check_action, check_options, check_vector
from sigmapi.envs.icub.frames import REACH_REGION, random_ball, random_gaze
from sigmapi.envs.icub.model import BALL_RADIUS
from sigmapi.envs.icub.reach import physical_reach
from sigmapi.envs.icub.scene import EYE_SIZE, GAZE, ICubScene
from sigmapi.errors import ConfigError

__all__ = ["ENV_ID", "RETINA_SOURCES", "ArmAction", "ICubReachEnv"]

ENV_ID = "sigmapi/ICubReach-v0"
"""The environment's Gymnasium id (registered by ``import sigmapi``)."""
RETINA_SOURCES = ("projection", "pixels")
"""Where the observed retina comes from: the exact projection or the rendered pixels."""

Obs = dict[str, NDArray[np.float32]]


class ArmAction:
    """An iCub environment's action: an arm posture, each joint's range (``_lo``, ``_hi``,
    radians) mapped onto [-1, 1]."""

    _lo: NDArray[np.float64]
    _hi: NDArray[np.float64]

    def posture(self, action: NDArray[np.generic]) -> NDArray[np.float64]:
        """The arm posture (radians) of an action in [-1, 1]^7."""
        a = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
        return self._lo + 0.5 * (a + 1.0) * (self._hi - self._lo)

    def action_of(self, posture: NDArray[np.generic]) -> NDArray[np.float32]:
        """The action (in [-1, 1]^7) of an arm posture (radians; clipped to the ranges)."""
        q = np.clip(np.asarray(posture, dtype=np.float64), self._lo, self._hi)
        return (2.0 * (q - self._lo) / (self._hi - self._lo) - 1.0).astype(np.float32)


class ICubReachEnv(ArmAction, gym.Env[Obs, NDArray[np.float32]]):
    """Reach for a ball on the table with the iCub's right arm, from a random gaze.

    Parameters
    ----------
    retina : {"projection", "pixels"}
        The observed retina: exact projection, or the red blob's centroid in the right eye's
        rendered frame.
    eye_size : int
        Side of each eye's square frame, pixels.
    render_mode : {None, "rgb_array"}
        ``"rgb_array"``: :meth:`render` returns a third-person view (240 x 320).
    """

    metadata: dict[str, object] = {"render_modes": ["rgb_array"], "render_fps": 10}  # noqa: RUF012
    reset_options: ClassVar[tuple[str, ...]] = ("ball", "gaze")
    """The names ``reset(options=...)`` takes."""

    def __init__(
        self, retina: str = "projection", eye_size: int = EYE_SIZE, render_mode: str | None = None
    ) -> None:
        if retina not in RETINA_SOURCES:
            raise ConfigError(f"retina must be one of {RETINA_SOURCES}, got {retina!r}")
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.retina_source, self.render_mode = retina, render_mode
        self.scene = ICubScene(eye_size)
        lim = np.float32(np.pi)
        self.observation_space = spaces.Dict(
            {  # type: ignore[assignment]
                "retina": spaces.Box(0.0, 1.0, (2,), np.float32),
                "gaze": spaces.Box(-lim, lim, (6,), np.float32),
                "arm": spaces.Box(-lim, lim, (7,), np.float32),
            }
        )
        self.action_space = spaces.Box(-1.0, 1.0, (7,), np.float32)
        self._lo, self._hi = self.scene.arm_range.T
        m = self.scene.model
        table = m.geom("table").id
        centre, half = m.geom_pos[table][:2], m.geom_size[table][:2] - BALL_RADIUS
        self.ball_region = np.stack([centre - half, centre + half], axis=1)
        """Where ``reset(options={"ball": (x, y)})`` may put the ball: the table top (world x
        and y rows, ``(low, high)``, metres; less the ball's radius at each edge)."""
        joint = {n: m.jnt_range[m.joint(n).id] for n in ("eyes_tilt", "r_eye_pan", *GAZE[3:])}
        pan, span = joint["r_eye_pan"], joint["r_eye_pan"][1] - joint["r_eye_pan"][0]
        self.gaze_range = np.array(
            [joint["eyes_tilt"], pan, (-span, span), *(joint[n] for n in GAZE[3:])]
        )
        """The gazes ``reset(options={"gaze": ...})`` takes (:data:`GAZE` rows, ``(low,
        high)``, radians): each joint within its range (the eyes' version and vergence also
        keep each eye's pan within its range)."""

    def _retina(self) -> NDArray[np.float64]:
        s = self.scene
        uv = s.ball_pixels("r_eye") if self.retina_source == "pixels" else None
        if uv is None:  # projection, or a ball hidden by the hand: the projection
            uv = s.project(s.ball_position())[0]
        return np.asarray(uv) / s.eye_size

    def _obs(self) -> Obs:
        s = self.scene
        return {
            "retina": np.clip(self._retina(), 0, 1).astype(np.float32),
            "gaze": s.gaze().astype(np.float32),
            "arm": s.arm().astype(np.float32),
        }

    def reset(
        self, *, seed: int | None = None, options: dict[str, object] | None = None
    ) -> tuple[Obs, dict[str, object]]:
        """A new ball and gaze; ``options={"ball": (x, y), "gaze": six angles}`` fixes them:
        the ball on the table (:attr:`ball_region`), the gaze within the joints' ranges
        (:attr:`gaze_range`); else one :class:`~sigmapi.errors.ConfigError` line."""
        options = check_options(options, self.reset_options, "ICubReach")
        ball, gaze = options.get("ball"), options.get("gaze")
        if ball is not None:
            ball = check_vector(
                "options['ball']",
                ball,
                (2,),
                *self.ball_region.T,
                unit="(world x, y, metres)",
                fix="a place on the table",
            )
        if gaze is not None:
            gaze = self._check_gaze(gaze)
        super().reset(seed=seed)
        s = self.scene
        s.reset()
        s.set_ball(random_ball(self.np_random, 1, REACH_REGION)[0] if ball is None else ball)
        if gaze is None:
            random_gaze(s, s.ball_position(), self.np_random)
        else:
            s.set_gaze(gaze)
        s.hold()
        return self._obs(), self._info()

    def _check_gaze(self, value: Any) -> NDArray[np.float64]:
        fix = f"the angles {GAZE}, each within its joint's range"
        g = check_vector(
            "options['gaze']", value, (6,), *self.gaze_range.T, unit="(radians)", fix=fix
        )
        pans = g[1] + np.array([0.5, -0.5]) * g[2]  # the left and the right eye's pan
        lo, hi = self.gaze_range[1]
        if np.any(pans < lo) or np.any(pans > hi):
            raise ConfigError(
                f"options['gaze'] must keep each eye's pan (version +- vergence / 2) in "
                f"[{lo:.4g}, {hi:.4g}], got version {g[1]:.4g} and vergence {g[2]:.4g}; {fix}"
            )
        return g

    def _info(self) -> dict[str, object]:
        s = self.scene
        return {"ball": s.ball_position(), "torso_direction": s.torso_direction(s.ball_position())}

    def step(
        self, action: NDArray[np.float32]
    ) -> tuple[Obs, SupportsFloat, bool, bool, dict[str, object]]:
        """Reach for posture ``action`` (7 finite numbers in [-1, 1]: :meth:`posture`; else one
        :class:`~sigmapi.errors.ConfigError` line); the episode ends (terminated) with the reach."""
        a = check_action(self.action_space, action, fix="each joint's range mapped onto [-1, 1]")
        out = physical_reach(self.scene, self.posture(a))
        info = {**self._info(), "is_success": out.touched, "distance": out.distance}
        return self._obs(), float(out.touched), True, False, info

    def render(self) -> NDArray[np.uint8] | None:
        """A third-person view (``render_mode="rgb_array"``), else None."""
        return self.scene.render("third") if self.render_mode == "rgb_array" else None

    def render_eyes(self) -> tuple[NDArray[np.uint8], NDArray[np.uint8]]:
        """Both eyes' frames now, ``(left, right)``, each ``(eye_size, eye_size, 3)`` uint8
        (the body hidden but the right forearm and hand)."""
        return self.scene.render("l_eye"), self.scene.render("r_eye")

    def close(self) -> None:
        """Free the renderers."""
        self.scene.close()
