"""ICubReach3D: the iCub sees a ball in the air with both eyes and reaches for it, palm first.

The 3-D task of :mod:`~sigmapi.experiments.icub.reach3d` as a Gymnasium environment. One reach
is one episode of one step. ``reset`` floats the ball (:func:`~sigmapi.envs.icub.stereo.float_ball`)
at a random place of :data:`~sigmapi.envs.icub.stereo.BOX` (or ``options={"ball": (x, y, z)}``),
puts the arm at home and looks for the ball with random head postures and eye commands until
both eyes see it (:func:`~sigmapi.experiments.icub.reach3d.look`; a ball the eyes cannot find
is put elsewhere). The observation is what the robot senses: ``"left"`` and ``"right"``, the
ball's detected pixel in each eye's rendered frame as a fraction of its side
(``(u, v) / eye_size``), ``"gaze"``, the six gaze angles (radians,
:data:`~sigmapi.envs.icub.scene.GAZE`) and ``"arm"``, the right arm's seven joint angles. The
action is an arm posture, each joint's range mapped onto [-1, 1]; the step reaches it in the
physics (:func:`~sigmapi.experiments.icub.reach3d.reach3d`: from above and behind, the touch
stops the arm) and ends the episode: reward 1 and ``info["is_success"]`` on the 3-D task's
strict success (the palm touched the ball and it moved less than
:data:`~sigmapi.experiments.icub.reach3d.MOVED`), else 0; ``info`` also holds the touch, the
palm's touch, the end-point error and how far the ball moved (the scorer's readings).
"""

from __future__ import annotations

from typing import ClassVar, SupportsFloat

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from sigmapi.envs.checks import check_action, check_options, check_vector
from sigmapi.envs.icub import stereo as st
from sigmapi.envs.icub.env import PLACEMENTS, ArmAction, nothing_seen
from sigmapi.envs.icub.scene import EYE_SIZE, ICubScene
from sigmapi.errors import ConfigError
from sigmapi.experiments.icub.reach3d import look, reach3d

__all__ = ["ENV_ID", "ICubReach3DEnv"]

ENV_ID = "sigmapi/ICubReach3D-v0"
"""The environment's Gymnasium id (registered by ``import sigmapi``)."""

Obs = dict[str, NDArray[np.float32]]


class ICubReach3DEnv(ArmAction, gym.Env[Obs, NDArray[np.float32]]):
    """Reach for a ball in the air with the iCub's right arm, palm first, seen by both eyes.

    Parameters
    ----------
    eye_size : int
        Side of each eye's square frame, pixels.
    render_mode : {None, "rgb_array"}
        ``"rgb_array"``: :meth:`render` returns a third-person view.
    """

    metadata: dict[str, object] = {"render_modes": ["rgb_array"], "render_fps": 10}  # noqa: RUF012
    reset_options: ClassVar[tuple[str, ...]] = ("ball",)
    """The names ``reset(options=...)`` takes."""

    def __init__(self, eye_size: int = EYE_SIZE, render_mode: str | None = None) -> None:
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.render_mode = render_mode
        self.scene = ICubScene(eye_size)
        st.float_ball(self.scene)
        lim = np.float32(np.pi)
        self.observation_space = spaces.Dict(
            {  # type: ignore[assignment]
                "left": spaces.Box(0.0, 1.0, (2,), np.float32),
                "right": spaces.Box(0.0, 1.0, (2,), np.float32),
                "gaze": spaces.Box(-lim, lim, (6,), np.float32),
                "arm": spaces.Box(-lim, lim, (7,), np.float32),
            }
        )
        self.action_space = spaces.Box(-1.0, 1.0, (7,), np.float32)
        self._lo, self._hi = self.scene.arm_range.T
        self._seen: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None

    def _obs(self) -> Obs:
        s = self.scene
        left, right = self._seen if self._seen is not None else (np.zeros(2), np.zeros(2))
        return {
            "left": np.clip(np.asarray(left) / s.eye_size, 0, 1).astype(np.float32),
            "right": np.clip(np.asarray(right) / s.eye_size, 0, 1).astype(np.float32),
            "gaze": s.gaze().astype(np.float32),
            "arm": s.arm().astype(np.float32),
        }

    def reset(
        self, *, seed: int | None = None, options: dict[str, object] | None = None
    ) -> tuple[Obs, dict[str, object]]:
        """A new ball and gaze; ``options={"ball": (x, y, z)}`` fixes the ball (world metres,
        inside :data:`~sigmapi.envs.icub.stereo.BOX`); else one
        :class:`~sigmapi.errors.ConfigError` line. A fixed ball the eyes cannot find after
        every search is a :class:`~sigmapi.errors.ConfigError` too."""
        options = check_options(options, self.reset_options, "ICubReach3D")
        ball = options.get("ball")
        if ball is not None:
            ball = check_vector(
                "options['ball']",
                ball,
                (3,),
                *st.BOX.T,
                unit="(world x, y, z, metres)",
                fix="a point of the arm's box sigmapi.envs.icub.stereo.BOX",
            )
        super().reset(seed=seed)
        s, rng = self.scene, self.np_random
        for _ in range(PLACEMENTS):
            s.reset()
            p = st.random_point(rng, 1)[0] if ball is None else ball
            st.place_ball(s, p)
            self._seen = look(s, rng, "ball")
            if self._seen is not None:
                break
            if ball is not None:
                raise ConfigError(
                    f"options['ball'] must be a point both eyes can find, got "
                    f"{np.round(ball, 4).tolist()}; another point of the box"
                )
        else:
            raise nothing_seen(PLACEMENTS)
        return self._obs(), self._info()

    def _info(self) -> dict[str, object]:
        with self.scene.truth():
            return {"ball": self.scene.ball_position()}

    def step(
        self, action: NDArray[np.float32]
    ) -> tuple[Obs, SupportsFloat, bool, bool, dict[str, object]]:
        """Reach for posture ``action`` (7 finite numbers in [-1, 1]: :meth:`posture`; else one
        :class:`~sigmapi.errors.ConfigError` line); the episode ends (terminated) with the reach."""
        a = check_action(self.action_space, action, fix="each joint's range mapped onto [-1, 1]")
        info = self._info()
        r = reach3d(self.scene, self.posture(a))
        info |= {
            "is_success": r.strict,
            "touched": r.touched,
            "palm": r.palm,
            "end_point": r.end_point,
            "moved": r.moved,
        }
        self._seen = st.see_both(self.scene)
        return self._obs(), float(r.strict), True, False, info

    def render(self) -> NDArray[np.uint8] | None:
        """A third-person view (``render_mode="rgb_array"``), else None."""
        return self.scene.render("third") if self.render_mode == "rgb_array" else None

    def render_eyes(self) -> tuple[NDArray[np.uint8], NDArray[np.uint8]]:
        """Both eyes' frames now, ``(left, right)``, each ``(eye_size, eye_size, 3)`` uint8."""
        return self.scene.render("l_eye"), self.scene.render("r_eye")

    def close(self) -> None:
        """Free the renderers."""
        self.scene.close()
