"""ICubReach: the iCub looks for a ball on the table and reaches for it.

One reach is one episode of one step. ``reset`` puts the ball at a random place of the arm's
reach (:data:`~sigmapi.envs.icub.frames.REACH_REGION`; the experimenter), the arm at home, and
the robot looks for the ball: random gaze commands, uniform in the gazes' range, until the
right eye's detector sees it (:func:`~sigmapi.envs.icub.frames.search`); a ball the eyes do
not find is put elsewhere, as the experimenter would. The observation is what the robot
senses: ``"retina"``, where the colour detector (:mod:`~sigmapi.envs.icub.detect`) finds the
ball in the right eye's rendered frame, as a fraction of its side (``(u, v) / eye_size``),
``"gaze"``, the six gaze angles (radians, :data:`~sigmapi.envs.icub.scene.GAZE`) and
``"arm"``, the right arm's seven joint angles. Where the eye does not see the ball (a gaze
fixed by ``reset(options=...)`` that looks elsewhere, or after a reach, the hand in the way
and a search that did not find it) the retina is ``(0, 0)``: a detection never touches the
image's border, so no detection reads ``(0, 0)``. The action is an arm posture, each joint's
range mapped onto [-1, 1]; the step moves the arm there in the physics, approaching from above
(:func:`~sigmapi.envs.icub.reach.physical_reach`), and ends the episode: reward 1 and
``info["is_success"]`` when the hand touched the ball, else 0; where the eye lost the ball in
the reach it looks for it again (:func:`~sigmapi.envs.icub.frames.search`). The simulator's
truth (the ball's place, its torso-centred direction, the palm's closest distance) is in
``info`` only, for scoring.

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
from sigmapi.envs.icub.frames import REACH_REGION, random_ball, search
from sigmapi.envs.icub.model import BALL_RADIUS
from sigmapi.envs.icub.reach import physical_reach
from sigmapi.envs.icub.scene import EYE_SIZE, GAZE, ICubScene
from sigmapi.errors import ConfigError

__all__ = ["ENV_ID", "PLACEMENTS", "ArmAction", "ICubReachEnv", "nothing_seen"]

ENV_ID = "sigmapi/ICubReach-v0"
"""The environment's Gymnasium id (registered by ``import sigmapi``)."""

Obs = dict[str, NDArray[np.float32]]

PLACEMENTS = 20
"""Balls the experimenter puts at ``reset`` (each looked for by the robot) before the reset
gives up with a RuntimeError: the eyes finding none at all means the frames show no ball."""


def nothing_seen(n: int) -> RuntimeError:
    """The reset's error when the eyes found none of ``n`` balls put in view."""
    return RuntimeError(
        f"the eyes found none of {n} balls put within view: the rendered frames show no ball "
        "(check the renderer, e.g. MUJOCO_GL=egl, with env.unwrapped.render_eyes())"
    )


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
    """Reach for a ball on the table with the iCub's right arm, seen by the right eye.

    Parameters
    ----------
    eye_size : int
        Side of each eye's square frame, pixels.
    render_mode : {None, "rgb_array"}
        ``"rgb_array"``: :meth:`render` returns a third-person view (240 x 320).
    """

    metadata: dict[str, object] = {"render_modes": ["rgb_array"], "render_fps": 10}  # noqa: RUF012
    reset_options: ClassVar[tuple[str, ...]] = ("ball", "gaze")
    """The names ``reset(options=...)`` takes."""

    def __init__(self, eye_size: int = EYE_SIZE, render_mode: str | None = None) -> None:
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.render_mode = render_mode
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
        self._seen: NDArray[np.float64] | None = None
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

    def _obs(self) -> Obs:
        s = self.scene
        uv = np.zeros(2) if self._seen is None else self._seen / s.eye_size
        return {
            "retina": np.clip(uv, 0, 1).astype(np.float32),
            "gaze": s.gaze().astype(np.float32),
            "arm": s.arm().astype(np.float32),
        }

    def reset(
        self, *, seed: int | None = None, options: dict[str, object] | None = None
    ) -> tuple[Obs, dict[str, object]]:
        """A new ball and gaze; ``options={"ball": (x, y), "gaze": six angles}`` fixes them:
        the ball on the table (:attr:`ball_region`), the gaze within the joints' ranges
        (:attr:`gaze_range`); else one :class:`~sigmapi.errors.ConfigError` line. Without a
        fixed gaze the robot searches for the ball (a drawn ball it does not find is put
        elsewhere; a fixed one is a :class:`~sigmapi.errors.ConfigError`); a fixed gaze is
        kept, seeing the ball or not."""
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
        s, rng = self.scene, self.np_random
        for _ in range(PLACEMENTS):
            s.reset()
            s.set_ball(random_ball(rng, 1, REACH_REGION)[0] if ball is None else ball)
            if gaze is not None:
                s.set_gaze(gaze)
                self._seen = s.see("ball")
                break
            self._seen = self._look()
            if self._seen is not None:
                break
            if ball is not None:
                raise ConfigError(
                    f"options['ball'] must be a place the right eye can find, got "
                    f"{np.round(ball, 4).tolist()}; another place on the table"
                )
        else:
            raise nothing_seen(PLACEMENTS)
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

    def _look(self) -> NDArray[np.float64] | None:
        """The robot's own looking (random gazes until the right eye sees the ball,
        :func:`~sigmapi.envs.icub.frames.search`): where it sees the ball, or None."""
        found = search(self.scene, self.np_random)
        return None if found is None else found[0]

    def _info(self) -> dict[str, object]:
        s = self.scene
        with s.truth():  # the scorer's readings, never observed
            p = s.ball_position()
            return {"ball": p, "torso_direction": s.torso_direction(p)}

    def step(
        self, action: NDArray[np.float32]
    ) -> tuple[Obs, SupportsFloat, bool, bool, dict[str, object]]:
        """Reach for posture ``action`` (7 finite numbers in [-1, 1]: :meth:`posture`; else one
        :class:`~sigmapi.errors.ConfigError` line); the episode ends (terminated) with the reach.
        Where the reach hid or moved the ball the robot looks for it again (random gazes)."""
        a = check_action(self.action_space, action, fix="each joint's range mapped onto [-1, 1]")
        s = self.scene
        out = physical_reach(s, self.posture(a))
        self._seen = s.see("ball")
        if self._seen is None:
            self._seen = self._look()
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
