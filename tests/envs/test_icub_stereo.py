"""The iCub's 3-D space: the floating ball, both eyes' detections, the fixation, depth.

Skipped where MuJoCo, ``icub-models`` or an OpenGL context is missing, except under
``CI=true`` (as ``tests/envs/test_icub.py``).
"""

from __future__ import annotations

import os

import numpy as np
import pytest

os.environ.setdefault("MUJOCO_GL", "egl")
if os.environ.get("CI") == "true":
    import icub_models  # noqa: F401
    import mujoco  # noqa: F401
else:
    pytest.importorskip("mujoco")
    pytest.importorskip("icub_models")

from sigmapi.envs.icub import ICubScene, TruthLeak
from sigmapi.envs.icub import stereo as st


@pytest.fixture(scope="module")
def scene() -> ICubScene:
    s = ICubScene()
    try:
        s.render("r_eye")
    except Exception as exc:  # no GL context: mujoco raises its own errors
        if os.environ.get("CI") == "true":
            pytest.fail(f"rendering must work under CI=true (MUJOCO_GL=egl): {exc}")
        pytest.skip(f"no OpenGL context here: {exc}")
    st.float_ball(s)
    s.seal()
    return s


def _looked_at(scene: ICubScene, rng: np.random.Generator, p: np.ndarray):
    """The ball put at ``p``; random necks until both eyes find it (what the robot does)."""
    st.place_ball(scene, p)
    for _ in range(4):
        scene.set_gaze([0.0, 0.0, 0.2, *st.random_neck3d(rng)])
        seen = st.search_both(scene, rng, tries=100)
        if seen is not None:
            return seen
    return None


def test_the_ball_floats_where_it_is_put(scene: ICubScene):
    p = np.array([0.25, -0.15, 0.75])
    st.place_ball(scene, p)
    scene.step(0.3)
    with scene.truth():
        assert np.linalg.norm(scene.ball_position() - p) < 1e-3
    with pytest.raises(TruthLeak):  # sealed: only scoring reads where it is
        scene.ball_position()


def test_the_box_is_the_issues_size():
    depth, width, height = np.diff(st.BOX, axis=1)[:, 0]
    assert depth >= 0.2 - 1e-9 and height >= 0.2 - 1e-9 and width > 0.0


def test_fixation_converges_and_depth_is_recovered(scene: ICubScene):
    rng = np.random.default_rng(7)
    free_err, fix_err, verg_err, steps = [], [], [], []
    for p in st.random_point(rng, 12):
        seen = _looked_at(scene, rng, p)
        assert seen is not None, f"neither search found the ball at {p}"
        truth = st.head_position(scene, p)
        # eyes free: depth from the disparity of the two detections
        free_err.append(
            np.linalg.norm(st.triangulate(scene.gaze(), *seen, 64, scene.focal) - truth)
        )
        out = st.fixate(scene)
        if out is None:
            continue
        (left, right), k = out
        steps.append(k)
        truth = st.head_position(scene, p)  # the neck may have turned
        assert max(abs(left[0] - 32), abs(right[0] - 32)) <= 0.5
        fix_err.append(
            np.linalg.norm(st.triangulate(scene.gaze(), left, right, 64, scene.focal) - truth)
        )
        # the vergence alone: both eyes' rays through their centres
        centre = np.array([32.0, 32.0])
        verg_err.append(
            np.linalg.norm(st.triangulate(scene.gaze(), centre, centre, 64, scene.focal) - truth)
        )
    assert len(steps) >= 11  # fixated 11 of 12 or more
    assert np.median(steps) <= 3
    assert np.median(free_err) < 0.006 and max(free_err) < 0.02
    assert np.median(fix_err) < 0.005 and max(fix_err) < 0.015
    assert np.median(verg_err) < 0.01 and max(verg_err) < 0.03


def test_the_triangulation_is_exact_on_exact_rays():
    # a point 30 cm ahead, 5 cm left, 10 cm down of the right eye, eyes at a known gaze
    p = np.array([0.3, 0.05, -0.1])
    f, c = 68.6, 32.0
    tilt, pl, pr = -0.2, 0.05, -0.1

    def pixel(eye: np.ndarray, pan: float) -> np.ndarray:
        d = p - eye
        ct, s = np.cos(tilt), np.sin(tilt)
        d = np.array([ct * d[0] + s * d[2], d[1], -s * d[0] + ct * d[2]])  # undo the tilt
        cp, sp = np.cos(pan), np.sin(pan)
        d = np.array([cp * d[0] - sp * d[1], sp * d[0] + cp * d[1], d[2]])  # undo the pan
        return np.array([c - f * d[1] / d[0], c - f * d[2] / d[0]])

    gaze = [tilt, 0.5 * (pl + pr), pl - pr, 0.0, 0.0, 0.0]
    left = pixel(np.array([0.0, 2 * st.EYE_HALF, 0.0]), pl)
    right = pixel(np.zeros(3), pr)
    assert np.allclose(st.triangulate(gaze, left, right, 64, f), p, atol=1e-9)
    wrong = st.triangulate(
        gaze, left + np.array([3.0, 0.0]), right, 64, f
    )  # a disparity error moves it
    assert np.linalg.norm(wrong - p) > 0.01
