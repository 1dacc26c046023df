"""The iCub's reaches in 3-D: the palm's contacts, the reach's scores, babbling on a sealed
scene, the states, the pooled result and ``sigmapi icub --space box``.

The scene tests need MuJoCo, ``icub-models`` and an OpenGL context; the result's tests none.
"""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

os.environ.setdefault("MUJOCO_GL", "egl")

from sigmapi.errors import ConfigError
from sigmapi.experiments.icub.box import ICubBoxResult
from sigmapi.experiments.icub.config import QUICK, ICubConfig
from sigmapi.experiments.icub.reach3d import METHODS


def _scene():
    pytest.importorskip("mujoco")
    pytest.importorskip("icub_models")
    from sigmapi.envs.icub import ICubScene
    from sigmapi.envs.icub import stereo as st

    scene = ICubScene()
    try:
        scene.render("r_eye")
    except Exception as exc:  # no GL context
        pytest.skip(f"no OpenGL context here: {exc}")
    st.float_ball(scene)
    return scene


def _palm_frame(scene):
    with scene.truth():
        return scene.palm_position(), scene.data.site_xmat[scene._palm].reshape(3, 3).copy()


def test_a_touch_counts_as_the_palms_only_on_the_palms_side():
    from sigmapi.envs.icub import stereo as st
    from sigmapi.envs.icub.model import BALL_RADIUS, HOME_ARM
    from sigmapi.experiments.icub import reach3d as r3

    scene = _scene()
    scene.set_arm(HOME_ARM)
    c, r = _palm_frame(scene)
    n = r[:, 2]  # the palm's normal
    for where, palm in ((c + (BALL_RADIUS - 0.002) * n, True), (c - 0.066 * n, False)):
        st.place_ball(scene, where)
        scene._mj.mj_collision(scene.model, scene.data)
        assert r3._contacts(scene) == (True, palm)
    st.place_ball(scene, c + 0.2 * n)  # well off the hand
    scene._mj.mj_collision(scene.model, scene.data)
    assert r3._contacts(scene) == (False, False)


def test_the_hand_spans_what_the_end_point_diagram_draws():
    """HAND_SPAN (the diagram's hand) against the mesh: its vertices along the palm's normal
    from the palm's contact point, within 1 mm."""
    from sigmapi.envs.icub.model import HAND_SPAN, HOME_ARM

    scene = _scene()
    scene.set_arm(HOME_ARM)
    m, d = scene.model, scene.data
    c, r = _palm_frame(scene)
    meshes = [g for g in np.flatnonzero(scene._hand) if m.geom_type[g] == 7]  # mjGEOM_MESH
    along = []
    for g in meshes:
        first, n = m.mesh_vertadr[m.geom_dataid[g]], m.mesh_vertnum[m.geom_dataid[g]]
        world = m.mesh_vert[first : first + n] @ d.geom_xmat[g].reshape(3, 3).T + d.geom_xpos[g]
        along.append((world - c) @ r[:, 2])
    a = np.concatenate(along)
    np.testing.assert_allclose([-a.min(), a.max()], HAND_SPAN, atol=1e-3)


def test_the_palms_middle_is_a_patch_across_the_palm_not_along_its_normal():
    from sigmapi.envs.icub.model import HOME_ARM

    scene = _scene()
    scene.set_arm(HOME_ARM)
    c, r = _palm_frame(scene)
    n, across = r[:, 2], r[:, 0]
    points = np.array([c + 0.02 * n, c - 0.03 * n, c + 0.02 * across, c + 0.04 * across])
    assert scene.palm_patch(points, 0.03).tolist() == [True, True, True, False]


def test_the_skin_feels_the_ball_on_the_palm_apart_from_the_rest_of_the_arm():
    from sigmapi.envs.icub import stereo as st
    from sigmapi.envs.icub.model import BALL_RADIUS, HOME_ARM
    from sigmapi.experiments.icub import reach3d as r3

    scene = _scene()
    scene.set_arm(HOME_ARM)
    c, r = _palm_frame(scene)
    n = r[:, 2]
    scene.seal()  # the skin is a sensor: it reads no truth
    for where, felt in (
        (c + (BALL_RADIUS - r3.TOUCH_DEPTH) * n, (True, False)),  # on the palm
        (c - 0.066 * n, (False, True)),  # against the back of the hand
        (c + 0.2 * n, (False, False)),  # off the hand
    ):
        st.place_ball(scene, where)
        assert scene.skin(r3.PALM_SIDE) == felt


def test_the_reach_starts_with_the_hand_out_of_the_box():
    from sigmapi.envs.icub import stereo as st
    from sigmapi.envs.icub.model import BALL_RADIUS
    from sigmapi.experiments.icub import reach3d as r3

    scene = _scene()
    scene.set_arm(r3.START_ARM)
    with scene.truth():
        c = scene.palm_position()
    lo, hi = st.BOX[:, 0] - BALL_RADIUS, st.BOX[:, 1] + BALL_RADIUS
    assert np.any((c < lo) | (c > hi))  # no ball in the box is in the start pose's way


def test_the_scripted_reach_puts_the_palm_on_the_ball_first():
    from sigmapi.envs.icub import stereo as st
    from sigmapi.experiments.icub import reach3d as r3

    scene = _scene()
    scene.seal()
    rng = np.random.default_rng(11)
    hits = []
    for _ in range(6):
        scene.reset()
        p = r3._reachable(scene, rng)
        q, left = r3.scripted_ik(scene, p)
        assert left < 0.01
        st.place_ball(scene, p)
        hits.append(r3.reach3d(scene, q))
    # palm first: the old reach (the marker at the ball's centre, from the home pose through
    # the lifted elbow) touched first with the palm on 0.49 of such balls, moved them on 0.38
    assert sum(h.strict for h in hits) >= 4
    assert np.median([h.end_point for h in hits]) < 0.015


def test_reach_scores_the_end_point_the_aim_and_the_balls_move():
    from sigmapi.envs.icub import stereo as st
    from sigmapi.envs.icub.model import REST_ARM
    from sigmapi.experiments.icub import reach3d as r3

    scene = _scene()
    scene.seal()
    rng = np.random.default_rng(3)
    p = r3._reachable(scene, rng)
    q, left = r3.scripted_ik(scene, p)
    assert left < 0.01
    st.place_ball(scene, p)
    hit = r3.reach3d(scene, q)
    assert hit.touched and hit.aim < 0.01
    # the reach ends where the arm first touched the ball: the palm, or at worst a fingertip
    # (the hand spans 9.6 cm ahead of the palm's contact point)
    assert hit.end_point < 0.12
    # a posture far from the ball: no touch, the ball stays, the palm ends far off
    scene.reset()
    st.place_ball(scene, p)
    far = np.array(REST_ARM)  # hanging at the side
    with scene.truth():
        scene.set_arm(far)
        gap = float(np.linalg.norm(r3._touch_point(scene) - p))
    miss = r3.reach3d(scene, far)
    assert not miss.touched and not miss.strict and miss.moved < 1e-3
    assert miss.aim == pytest.approx(gap) and miss.end_point > 0.05


def test_the_follow_through_finds_a_ball_beyond_the_posture(monkeypatch):
    from sigmapi.envs.icub import stereo as st
    from sigmapi.experiments.icub import reach3d as r3

    scene = _scene()
    rng = np.random.default_rng(5)
    p = r3._reachable(scene, rng)
    q, _ = r3.scripted_ik(scene, p)
    with scene.truth():  # the ball 2 cm further along the palm's facing than the posture holds
        scene.set_arm(q)
        far = p + 0.02 * scene.data.site_xmat[scene._palm].reshape(3, 3)[:, 2]
    scene.seal()
    st.place_ball(scene, far)
    on = r3.reach3d(scene, q)
    assert on.touched and on.strict
    monkeypatch.setattr(r3, "FOLLOW_THROUGH", 0.0)
    scene.reset()
    st.place_ball(scene, far)
    short = r3.reach3d(scene, q)
    assert not short.touched and short.end_point > 0.015


def test_babbling_and_reaching_in_3d_read_no_truth_outside_the_scores():
    from sigmapi.agents import Association
    from sigmapi.envs.icub import stereo as st
    from sigmapi.experiments.icub import reach3d as r3
    from sigmapi.experiments.icub import space3d as s3

    scene = _scene()
    scene.seal()  # every truth reader raises outside scene.truth()
    rng = np.random.default_rng(0)
    bab = r3.babble3d(scene, 12, rng, yaw=0.8, wrist=(-0.6, -0.3))
    assert bab.posture.shape == (12, 7) and bab.views.n == 12 and bab.tried >= 12
    with scene.truth():  # each kept posture rests the ball it saw on the palm
        for q, t in zip(bab.posture, bab.views.torso, strict=True):
            scene.set_arm(q)
            seen_at = st.torso_position(scene, r3._touch_point(scene))
            assert np.linalg.norm(seen_at - t) < 0.005
    assert np.all(np.isfinite(bab.views.left)) and np.all(np.isfinite(bab.views.torso))
    # swept: the arm moves into a ball held anywhere in the box; no truth read but its place
    swept = r3.babble3d(scene, 6, rng, yaw=0.8, wrist=(-0.6, -0.3), how="swept")
    assert swept.posture.shape == (6, 7) and swept.tried >= 6
    with scene.truth():  # each kept posture is the palm's first touch of the ball it saw
        for q, t in zip(swept.posture, swept.views.torso, strict=True):
            st.place_ball(scene, st.torso_to_world(scene, t))
            scene.set_arm(q)
            assert scene.skin(r3.PALM_SIDE, r3.PALM_PATCH) == (True, False)
            centre = np.linalg.norm(scene.palm_position() - st.torso_to_world(scene, t))
            assert centre < 0.05  # the ball on the palm's middle, not on the fingers
    with pytest.raises(ConfigError, match="babbling"):
        r3.babble3d(scene, 1, rng, yaw=0.8, wrist=(-0.6, -0.3), how="thrown")
    eyes = s3.record_pairs(scene, 20, rng, "eyes")
    head = s3.record_pairs(scene, 20, rng, "head")
    # tiny maps, each size given (the defaults are the measured design's)
    tiny = dict(grid=4, map_shape=(3, 3, 3), head_shape=None, torso_grid=None, depth_grid=None)
    chain = s3.learn_chain3d(eyes, head, iterations=100, seed=0, eye_size=64, **tiny)
    feats = r3.features3d(scene, chain, 4, 1.0, 1.0)
    # the learned chain, the retina and retina + gaze never read the labels
    blind = s3.Views3D(
        bab.views.left,
        bab.views.right,
        bab.views.gaze,
        bab.views.head * np.nan,
        bab.views.torso * np.nan,
    )
    for m in ("learned", "retina", "retina_gaze"):
        assert np.array_equal(feats(m, blind), feats(m, bab.views))
    # the learned state at map T's soft place: a bump between units, reading no labels either
    soft = r3.features3d(scene, chain, 4, 1.0, 1.0, state="soft")
    assert np.array_equal(soft("learned", blind), soft("learned", bab.views))
    peak = chain.map_t.map_coords[np.argmax(soft("learned", bab.views), axis=1)]
    assert np.all(np.abs(peak - chain.soft_grid_place("torso", bab.views)) <= 0.5 + 1e-9)
    assert np.isnan(feats("true_position", blind)).all()
    layers = {
        m: Association(feats(m, bab.views).shape[1], 7, epochs=2).fit(
            feats(m, bab.views), bab.posture
        )
        for m in r3.ASSOCIATED
    }
    tests, _ = r3.reach_tests3d(scene, layers, feats, 3, rng, bab.posture)
    out = r3.summarise(tests)
    assert set(out) == set(r3.CONDITIONS)
    for cond in r3.CONDITIONS:
        assert set(out[cond]) == set(METHODS)
        for m in METHODS:
            assert out[cond][m]["end_point_cm"]["p90"] >= out[cond][m]["end_point_cm"]["median"]
    # the reference and the chance rate do not depend on what the eyes did
    assert out["free"]["scripted_ik"] == out["fixated"]["scripted_ik"]
    assert tests.ik_error.shape == (3,) and np.all(tests.ik_error < r3.REACHABLE)


def test_the_test_balls_are_put_reachable_or_anywhere_in_the_box():
    from sigmapi.envs.icub import stereo as st
    from sigmapi.experiments.icub import reach3d as r3

    scene = _scene()
    scene.seal()
    box = np.asarray(st.BOX)
    rng = np.random.default_rng(123)
    anywhere = np.array([r3._test_ball(scene, rng, "box") for _ in range(150)])
    assert np.all((anywhere >= box[:, 0]) & (anywhere <= box[:, 1]))
    # "box" is the experimenter's uniform draw itself, one point per ball, no IK consulted
    assert np.array_equal(anywhere, st.random_point(np.random.default_rng(123), 150))
    missed = [r3.scripted_ik(scene, p)[1] >= r3.REACHABLE for p in anywhere]
    assert 0 < sum(missed) < 15  # 6 of these 150: the far, low corner lies beyond the arm
    near = r3._test_ball(scene, np.random.default_rng(1), "reachable")
    assert r3.scripted_ik(scene, near)[1] < r3.REACHABLE
    with pytest.raises(ValueError, match="balls"):
        r3._test_ball(scene, np.random.default_rng(0), "table")


def _record(
    seed: int, learned: list[float], strict: list[bool], ik: list[float] | None = None
) -> dict:
    maps = {
        "order_r2": 0.5,
        "order_r2_per_axis": [0.9, 0.96, 0.97],
        "ordered": False,
        "folded": True,
        "fold_score": 40.0,
        "error_cm": 6.0,
        "error_ratio_to_kmeans": 2.0,
        "true_position": {"order_r2": 0.9, "error_cm": 3.0},
        "kmeans": {"error_cm": 3.0},
    }
    ep = {m: [0.01 * (i + 1) for i in range(4)] for m in METHODS}
    ep["learned"] = learned
    st = {m: [False] * 4 for m in METHODS}
    st["learned"] = strict
    raw = {"end_point_m": {}, "aim_m": {}, "strict": {}, "touched": {}, "reaches": {}}
    for cond in ("free", "fixated"):
        raw["end_point_m"][cond] = ep
        raw["aim_m"][cond] = ep
        raw["strict"][cond] = st
        raw["touched"][cond] = {m: [True] * 4 for m in METHODS}
        raw["reaches"][cond] = {
            m: {
                "end_point_cm": {
                    "median": float(np.median(ep[m]) * 100),
                    "p90": float(np.percentile(ep[m], 90) * 100),
                },
                "strict_success": float(np.mean(st[m])),
            }
            for m in METHODS
        }
    return {
        "seed": seed,
        "maps": {"map_head": maps, "map_torso": maps},
        "fixation_converged": 1.0,
        "seconds": {"total": 10.0},
        "peak_rss_mb": 700.0,
        **raw,
        **({} if ik is None else {"ik_error_m": ik}),
    }


def test_the_box_result_pools_every_reach_and_judges_the_targets():
    res = ICubBoxResult(
        ICubConfig(space="box"),
        (5, 6),
        [
            _record(5, [0.005, 0.01, 0.015, 0.02], [True, True, True, True]),
            _record(6, [0.05, 0.06, 0.07, 0.08], [False, True, False, False]),
        ],
    )
    d = json.loads(json.dumps(res.to_dict()))
    assert d["space"] == "box" and d["seeds"] == [5, 6]
    assert set(d["methods"]) == set(METHODS)
    learned = d["methods"]["learned"]
    pooled = 100 * np.array([0.005, 0.01, 0.015, 0.02, 0.05, 0.06, 0.07, 0.08])
    assert learned["end_point_cm"]["median"] == pytest.approx(np.median(pooled))
    assert learned["end_point_cm"]["p90"] == pytest.approx(np.percentile(pooled, 90))
    assert learned["strict_success"] == pytest.approx(5 / 8)
    assert learned["fixated"]["strict_success"] == pytest.approx(5 / 8)
    assert d["maps"]["map_head"]["order_r2_per_axis"] == pytest.approx([0.9, 0.96, 0.97])
    assert d["maps"]["map_torso"]["folded_seeds"] == 2
    t = d["targets"]
    assert t["learned_end_point_cm"] is False  # a median of 3.5 cm
    assert t["seeds_met"]["learned_end_point_cm"] == 1  # seed 5's 1.25 cm
    assert t["seeds_met"]["learned_strict_success"] == 1
    assert t["random_posture_strict_success"] is True
    assert t["maps_ordered_all_seeds"] is False
    assert d["peak_memory_mb"] == 700.0
    assert d["balls"] is None  # records without the IK's errors
    text = res.table()
    for m in METHODS:
        assert m in text
    assert "map_torso" in text


def test_the_box_result_pools_the_reachable_balls_apart():
    ik = [0.002, 0.05, 0.004, 0.03]  # balls 1 and 3 of each seed beyond the arm
    res = ICubBoxResult(
        ICubConfig(space="box", box_balls="box"),
        (5, 6),
        [
            _record(5, [0.005, 0.01, 0.015, 0.02], [True, False, True, False], ik),
            _record(6, [0.05, 0.06, 0.07, 0.08], [False, False, True, True], ik),
        ],
    )
    balls = json.loads(json.dumps(res.to_dict()))["balls"]
    assert balls["placed"] == "box" and balls["reachable_share"] == 0.5
    learned = balls["reachable"]["learned"]
    assert learned["strict_success"] == pytest.approx(3 / 4)
    assert learned["end_point_cm"]["median"] == pytest.approx(np.median([0.5, 1.5, 5, 7]))
    assert "0.50 of them reachable" in res.table()
    with pytest.raises(ConfigError, match="box_balls"):
        ICubConfig(box_balls="table")


def test_the_space_is_a_declared_choice():
    assert ICubConfig().space == "table" and QUICK.space == "table"
    with pytest.raises(ConfigError, match="space"):
        ICubConfig(space="air")
    assert QUICK.box_pairs < ICubConfig().box_pairs
    assert ICubConfig(space="box", render="reach.gif").render == "reach.gif"  # the 3-D film
    with pytest.raises(ConfigError, match=r"render must be a file name ending in \.gif"):
        ICubConfig(space="box", render="reach.png")


def test_icub_help_shows_the_space_and_the_box_fields(capsys):
    from sigmapi.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["icub", "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    for flag in ("--space", "box", "--box-pairs", "--box-babbles"):
        assert flag in out


def test_icub_space_air_is_refused_in_one_line(capsys):
    from sigmapi.cli import main

    assert main(["icub", "--space", "air", "--json"]) == 2
    err = capsys.readouterr().err.strip()
    assert "space" in err and "air" in err and "\n" not in err


def test_a_box_result_reads_back_through_the_icub_result():
    from sigmapi.experiments.icub.result import ICubResult

    res = ICubBoxResult(
        ICubConfig(space="box"), (5,), [_record(5, [0.01, 0.02, 0.03, 0.04], [True] * 4)]
    )
    d = json.loads(json.dumps(res.to_dict()))
    back = ICubResult.from_dict(d)
    assert isinstance(back, ICubBoxResult) and back.config.space == "box"
    assert json.loads(json.dumps(back.to_dict())) == d


def test_sigmapi_icub_space_box_runs_and_writes_the_keys(tmp_path, capsys):
    _scene()  # MuJoCo, the models and a GL context, or a skip
    from sigmapi.cli import main

    rc = main(
        ["icub", "--space", "box", "--seeds", "7", "--box-pairs", "20", "--box-eval-pairs",
         "20", "--box-iterations", "50", "--box-babbles", "50", "--reaches", "2", "--json",
         "--out", str(tmp_path / "out"), "--quiet", "--render", str(tmp_path / "reach.gif")]
    )  # fmt: skip
    assert rc == 0
    d = json.loads(capsys.readouterr().out)
    assert d["space"] == "box" and set(d["methods"]) == set(METHODS)
    for m in METHODS:
        assert set(d["methods"][m]["end_point_cm"]) == {"median", "p90"}
        assert 0.0 <= d["methods"][m]["strict_success"] <= 1.0
    for name in ("map_head", "map_torso"):
        assert len(d["maps"][name]["order_r2_per_axis"]) == 3
        assert "order_r2" in d["maps"][name]
    for name in ("end_point_histogram", "film", "eyes", "map-slices"):  # the first seed's
        assert (tmp_path / "out" / f"{name}.png").exists()
    slices = (tmp_path / "out" / "map-slices.txt").read_text()
    for name in ("map_head", "map_torso"):  # the caption reads the scores
        s = d["maps"][name]  # one seed: its own numbers
        verdict = "folded" if s["per_seed"][0]["folded"] else "not flagged"
        assert f"{s['order_r2']:.2f}, {verdict} (fold score {s['fold_score']:.2f})" in slices
    assert "3-D box" in (tmp_path / "out" / "eyes.txt").read_text()
    assert (tmp_path / "reach.gif").read_bytes()[:6] == b"GIF89a"


def test_the_3d_gym_id_senses_both_eyes_scores_the_palm_and_refuses_bad_input():
    _scene()  # skips without MuJoCo, icub-models or a GL context
    import gymnasium as gym
    from gymnasium.utils.env_checker import check_env

    from sigmapi.envs.icub import stereo as st
    from sigmapi.experiments.icub import reach3d as r3

    env = gym.make("sigmapi/ICubReach3D-v0").unwrapped
    check_env(env, skip_render_check=True)
    rng = np.random.default_rng(5)
    won = []
    for seed in range(3):
        p = r3._reachable(env.scene, rng)
        obs, info = env.reset(seed=seed, options={"ball": p})
        np.testing.assert_allclose(info["ball"], p)
        seen = st.see_both(env.scene)  # the observation is both eyes' detections, in pixels
        assert seen is not None
        np.testing.assert_allclose(obs["left"] * env.scene.eye_size, seen[0], atol=1e-3)
        np.testing.assert_allclose(obs["right"] * env.scene.eye_size, seen[1], atol=1e-3)
        np.testing.assert_allclose(obs["gaze"], env.scene.gaze(), atol=1e-6)
        q = r3.scripted_ik(env.scene, p)[0]
        _, reward, done, _, info = env.step(env.action_of(q))
        assert done and reward == float(info["is_success"])
        won.append(info["is_success"])
    assert sum(won) >= 2  # the scripted reference's posture: palm first, the ball kept
    env.reset(seed=0, options={"ball": p})
    _, reward, _, _, info = env.step(-np.ones(7, np.float32))  # the arm's lower limits
    assert reward == 0.0 and not info["is_success"]
    for bad in (np.full(7, np.nan, np.float32), np.full(7, 2.0, np.float32)):
        with pytest.raises(ConfigError, match="action must be"):
            env.step(bad)
    for opt, says in (({"bal": 1}, "unknown reset option 'bal'"), ({"ball": (0, 0, 0)}, "ball")):
        with pytest.raises(ConfigError, match=says):
            env.reset(options=opt)
    env.close()
