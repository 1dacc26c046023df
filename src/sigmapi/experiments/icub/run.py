"""The iCub experiment: the frames checked, the chain of maps learned, reaching learned.

:data:`ICUB` (an :class:`ICubExperiment`) runs an
:class:`~sigmapi.experiments.icub.config.ICubConfig` on a list of seeds:

1. **Frames** (once, from :data:`~sigmapi.metrics.EVAL_SEED`): in ``frame_scenes`` random
   scenes (a ball on the table, a random gaze that keeps it in view) the red blob's centroid in
   the rendered right-eye frame against the exact projection, and the eye frame's render time.
   The maps and associations then read the retina from the projection.
2. **Per seed** (one job of the executor; everything random from ``SeedSequence(seed)``):
   map 1 and map 2 (:mod:`~sigmapi.experiments.icub.maps`), scored on evaluation pairs drawn
   once from the evaluation seed, beside a same-size map on the true directions and a cubic
   fit; babbling and the associations, their babbling curves; the reaches of every method
   (:mod:`~sigmapi.experiments.icub.reaching`).
"""

from __future__ import annotations

import dataclasses
import functools
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi import _memory
from sigmapi._outputs import check_file
from sigmapi.envs.icub import ICubScene, ViewBatch, random_gaze
from sigmapi.envs.icub.detect import TARGETS, detect
from sigmapi.envs.icub.frames import direction_ball, sensed_view
from sigmapi.envs.icub.model import REST_ARM, icub_models_module
from sigmapi.envs.robot.scene import check_rendering, mujoco_module
from sigmapi.errors import ConfigError
from sigmapi.experiments.base import Experiment, Run, register, run_all
from sigmapi.experiments.icub.box import ICubBoxResult, run_box
from sigmapi.experiments.icub.config import ICUB_WORLD, PLAN, QUICK, ICubConfig
from sigmapi.experiments.icub.maps import (
    ChainMaps,
    MapData,
    exact_map1,
    learn_chain,
    score,
    supervised_fit,
    true_direction_map,
)
from sigmapi.experiments.icub.reaching import (
    EYES,
    babble,
    eye_frames,
    features,
    film_first,
    learn_reaching,
    reach_tests,
)
from sigmapi.experiments.icub.result import ICubResult
from sigmapi.experiments.kit.jobs import Steps, Tick, counted
from sigmapi.metrics import EVAL_SEED, z_decoder
from sigmapi.progress import Progress


def check_frames(scene: ICubScene, n: int, rng: np.random.Generator) -> dict[str, Any]:
    """The detector (:mod:`sigmapi.envs.icub.detect`) against the exact projection over ``n``
    random scenes, each twice (a ball on the table with the arm at rest, and the hand on the
    table in a babbling posture; a gaze that keeps the ball, or the marker's centre, in the
    right eye's view; the simulator's truth scores it here): per
    target and eye the error in pixels and degrees, how often a target in view (its centre 4
    pixels inside) was missed and how often one out of view was reported; the right eye
    frame's render time and the detector's time per frame (wall and CPU milliseconds,
    medians). ``pixel_rms_px`` and ``pixel_max_px`` are the ball's in the right eye."""
    wall, cpu, det = [], [], []
    err: dict[tuple[str, str], list[float]] = {(t, e): [] for t in TARGETS for e in EYES}
    deg: dict[tuple[str, str], list[float]] = {(t, e): [] for t in TARGETS for e in EYES}
    missed = dict.fromkeys(err, 0)
    inview = dict.fromkeys(err, 0)
    false = dict.fromkeys(err, 0)
    scene.reset()
    lo, hi = scene.arm_range.T
    with scene.truth():
        for b in direction_ball(scene, rng, n):
            scene.reset()
            scene.set_ball(b)
            random_gaze(scene, scene.ball_position(), rng)  # the arm at rest, out of view
            scenes = [("ball", scene.gaze(), np.array(REST_ARM))]
            while True:  # the hand on the table somewhere, as babbling puts it
                q = np.zeros(7)
                q[[0, 1, 2, 3, 5]] = rng.uniform(lo[[0, 1, 2, 3, 5]], hi[[0, 1, 2, 3, 5]])
                scene.set_arm(q)
                if not scene.hand_on_table():
                    continue
                try:  # a marker under the table's edge: no gaze sees it
                    random_gaze(scene, scene.marker_position(), rng)
                    break
                except ConfigError:
                    continue
            scenes.append(("hand", scene.gaze(), q))
            for target, gaze, arm in scenes:
                scene.set_arm(arm)
                scene.set_gaze(gaze)
                point = scene.ball_position() if target == "ball" else scene.marker_position()
                for eye in EYES:
                    t0, c0 = time.perf_counter(), time.process_time()
                    img = scene.render(eye)
                    if eye == "r_eye" and target == "ball":
                        wall.append(time.perf_counter() - t0)
                        cpu.append(time.process_time() - c0)
                    t1 = time.perf_counter()
                    px = detect(img, target)
                    det.append(time.perf_counter() - t1)
                    truth = scene.project(point, eye)[0]
                    size = scene.eye_size
                    seen = bool(np.all((truth >= 4.0) & (truth <= size - 4.0)))
                    key = (target, eye)
                    inview[key] += seen
                    if px is None:
                        missed[key] += seen
                        continue
                    if not seen:
                        false[key] += 1
                        continue
                    err[key].append(float(np.linalg.norm(px - truth)))
                    deg[key].append(_angle_deg(scene, px, truth))
    scene.reset()
    ball = np.array(err["ball", "r_eye"])
    detector: dict[str, Any] = {"detect_ms_median": 1e3 * float(np.median(det))}
    for target, eye in err:
        e, a = np.array(err[target, eye]), np.array(deg[target, eye])
        detector.setdefault(target, {})[eye] = {
            "detected": int(e.size),
            "in_view": inview[target, eye],
            "missed": missed[target, eye],
            "false": false[target, eye],
            "error_px_median": float(np.median(e)) if e.size else None,
            "error_px_rms": float(np.sqrt(np.mean(e**2))) if e.size else None,
            "error_px_p90": float(np.percentile(e, 90)) if e.size else None,
            "error_deg_median": float(np.median(a)) if a.size else None,
            "error_deg_p90": float(np.percentile(a, 90)) if a.size else None,
        }
    return {
        "scenes": n,
        "hidden": n - int(ball.size),
        "pixel_rms_px": float(np.sqrt(np.mean(ball**2))),
        "pixel_max_px": float(ball.max()),
        "eye_size": scene.eye_size,
        "eye_frame_ms_median": 1e3 * float(np.median(wall)),
        "eye_frame_cpu_ms_median": 1e3 * float(np.median(cpu)),
        "detector": detector,
    }


def _angle_deg(scene: ICubScene, a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
    """The angle, degrees, between the camera rays through pixels ``a`` and ``b``."""
    c = 0.5 * scene.eye_size
    ra, rb = (np.array([p[0] - c, p[1] - c, scene.focal]) for p in (a, b))
    cos = ra @ rb / (np.linalg.norm(ra) * np.linalg.norm(rb))
    return float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))


@dataclass(frozen=True)
class _Job:
    config: ICubConfig
    seed: int
    cal: MapData
    test: MapData
    figures: bool
    show: Progress | None = None
    """Where given, the job shows its steps (:data:`STEPS`)."""


STEPS = (
    "record the training views",
    "learn map 1 and map 2",
    "score map 1",
    "score map 2",
    "babble",
    "learn to reach",
    "test the reaches",
)
"""The steps of one seed's job, as its progress names them."""


def learn_seed_chain(
    cfg: ICubConfig, seed: int, scene: ICubScene, steps: Steps | None = None
) -> tuple[MapData, ChainMaps]:
    """The training views and the chain of maps of ``seed`` (what :meth:`ICubExperiment.run`
    learns for that seed; ``sigmapi physiology`` records the same maps in
    ``benchmarks/bench_physiology.py --icub``); ``steps`` moves on when the views are
    recorded."""
    rng = PLAN.rng(seed, "views")
    train = MapData.record(
        scene, cfg.train_pairs, rng, cfg.moved_share, cfg.balls, cfg.pairs_per_ball
    )
    if steps is not None:
        steps.next()
    chain = learn_chain(
        train,
        grid=cfg.grid,
        width=cfg.code_width,
        map_shape=cfg.map_shape,
        iterations=cfg.iterations,
        seed=seed,
        eye_size=scene.eye_size,
        backend=cfg.backend,
        code=cfg.head_code,
        head_width=cfg.head_width,
    )
    return train, chain


def _run_seed(job: _Job) -> dict[str, Any]:
    """Maps, babbling and reaches of one seed."""
    work = functools.partial(_seed, job)
    return counted(job.show, len(STEPS), f"icub seed {job.seed}", work, "step")


def _seed(job: _Job, tick: Tick | None) -> dict[str, Any]:
    steps = Steps(tick, STEPS)
    cfg, seed = job.config, job.seed
    scene = ICubScene()
    scene.seal()  # the truth only where scene.truth() says: scoring and references
    t0 = time.process_time()
    train, chain = learn_seed_chain(cfg, seed, scene, steps)
    steps.next()
    out: dict[str, Any] = {"seed": seed, "maps": {}}
    for stage in (1, 2):
        m = score(chain, stage, job.cal, job.test)
        m["true_direction_map"] = true_direction_map(
            train, job.cal, job.test, stage, cfg.map_shape, cfg.iterations, seed
        )
        m["supervised"] = supervised_fit(train, job.test, stage, scene.eye_size)
        if stage == 2:
            m["exact_map1"] = exact_map1(chain, train, job.cal, job.test)
        out["maps"][f"map{stage}"] = m
        steps.next()
    out["map_cpu_s"] = time.process_time() - t0
    rng = PLAN.rng(seed, "babbling")
    wrist = (cfg.babble_wrist[0], cfg.babble_wrist[1])
    babbles = babble(scene, cfg.babbles, rng, yaw=cfg.babble_yaw, wrist=wrist)
    held_out = babble(scene, 200, rng, yaw=cfg.babble_yaw, wrist=wrist)
    steps.next()

    def feats(method: str, v: Any) -> NDArray[np.float64]:
        return features(method, v, chain, cfg.grid, cfg.code_width, cfg.feature_width, cfg.readout)

    layers, curves = learn_reaching(scene, babbles, held_out, feats, epochs=cfg.epochs)
    steps.next()
    tests, frames = reach_tests(
        scene,
        layers,
        feats,
        cfg.reaches,
        PLAN.rng(seed, "reaches"),
        film_first if job.figures else None,
        servo_steps=cfg.servo_steps,
        servo_rng=PLAN.rng(seed, "servo"),
        babbled=held_out.posture,
    )
    out.update(
        curves=curves,
        ball=tests.ball,
        gaze=tests.gaze,
        success=tests.success,
        servo=tests.servo,
        distance=tests.distance,
        cpu_s=time.process_time() - t0,
    )
    steps.next()
    if job.figures:
        c0 = job.cal.head[0]
        zc = z_decoder(chain.winner(c0, 2), c0.torso, chain.map2.map_coords)
        with scene.truth():  # the figure's map on the table (scored positions)
            out["unit_table"] = scene.table_point(zc)[:, :2]
        out["film"] = frames
        ball, gaze = tests.ball[0], tests.gaze[0]
        posture = layers["learned"].predict(feats("learned", _view(scene, ball, gaze)))[0]
        out["eyes"] = _eye_views(scene, ball, gaze, posture)
    scene.close()
    return out


def _view(scene: ICubScene, ball: NDArray[np.float64], gaze: NDArray[np.float64]) -> ViewBatch:
    """The view of the ball at ``gaze`` as the robot senses it (a reach test's first view)."""
    scene.reset()
    scene.set_ball(ball)
    scene.set_gaze(gaze)
    uv = scene.see("ball")
    if uv is None:
        raise RuntimeError("the ball a reach test saw is not seen again at the same gaze")
    cols = [np.array([c]) for c in sensed_view(scene, uv, scene.ball_position)]
    return ViewBatch(*cols)


def _eye_views(
    scene: ICubScene,
    ball: NDArray[np.float64],
    gaze: NDArray[np.float64],
    posture: NDArray[np.float64],
) -> dict[str, Any]:
    """Both eyes' frames with the arm at the learned posture for the ball, and where the ball
    and the palm project."""
    scene.reset()
    scene.set_ball(ball)
    scene.set_gaze(gaze)
    scene.set_arm(posture)
    out = eye_frames(scene)
    scene.reset()
    return out


class ICubExperiment(Experiment[ICubConfig]):
    """The iCub learns where things are from its own eyes and neck (a chain of two Sigma-Pi
    maps), and learns to reach from babbling; every reaching method side by side."""

    name = "icub"
    summary = "the iCub learns a chain of maps from its eyes and neck, then learns to reach"
    config_type = ICubConfig
    quick = QUICK
    seeds = ICUB_WORLD.seeds
    """The seeds of the acceptance run (:data:`~sigmapi.experiments.icub.config.SEEDS`)."""
    quick_seeds = (0,)
    """The seed of ``--quick``: a tuning seed."""
    quick_time = "about 3 min on two quiet cores, more on busy ones; --space box: 30 s"
    extra = "robot"
    default_out = "icub"

    def before_writing(self, config: ICubConfig, *, force: bool) -> None:
        """The ``--render`` file, checked before the work
        (:func:`~sigmapi._outputs.check_file`: its folder exists, no link, no file replaced
        without ``--force``)."""
        if config.render is not None:
            check_file(config.render, force=force, what="--render file")

    def execute(self, config: ICubConfig, run: Run) -> ICubResult | ICubBoxResult:
        """The frames check, then one job per seed (see the module's account); with
        ``config.space`` "box", the 3-D task (:func:`~sigmapi.experiments.icub.box.run_box`)."""
        seeds, executor, progress = run.seeds, run.executor, run.progress
        if config.space == "box":
            mujoco_module()
            icub_models_module()
            check_rendering()
            return run_box(config, seeds, executor=executor, progress=progress)
        _check_memory(config)  # every size that drives the work, before any of it
        mujoco_module()
        icub_models_module()  # before any work: both say which extra to install
        check_rendering()  # and that this machine renders (MUJOCO_GL)
        t0 = time.perf_counter()
        tick, bar = Progress.of(progress).counter(2, "icub", "step")
        with bar:
            steps = Steps(tick, ("check the frames", "record the evaluation views"))
            scene = ICubScene()
            scene.seal()  # the frames check and the evaluation's labels read it in truth()
            frames = check_frames(scene, config.frame_scenes, np.random.default_rng(EVAL_SEED))
            steps.next()
            cal, test = MapData.evaluation(
                scene, config.eval_pairs, config.balls, config.pairs_per_ball
            )
            steps.next()
            scene.close()
        jobs = [(str(seed), _Job(config, seed, cal, test, i == 0)) for i, seed in enumerate(seeds)]
        values = run_all(
            _run_seed,
            jobs,
            executor=executor,
            per_job=_job_memory(config),
            progress=progress,
            desc="icub",
            describe=lambda key, v: f"seed {key} ({v['cpu_s']:.0f} CPU s)",
            verbose=lambda job: dataclasses.replace(job, show=progress),
        )
        res = ICubResult(config, seeds, frames, [values[str(s)] for s in seeds])
        res.seconds = time.perf_counter() - t0
        return res


def _job_memory(config: ICubConfig) -> int:
    """Bytes of one job (an upper estimate): the maps' weights and trainer state, the codes
    of the training and evaluation views, the babbles' codes and features, the renderer."""
    n = config.grid**2
    units = int(np.prod(config.map_shape))
    weights = units * n * (n + units) * 8 * 6
    views = (config.train_pairs + 2 * config.eval_pairs) * 4 * 2 * (2 * n) * 8
    babbles = config.babbles * (4 * n + 2 * units + 16) * 8 * 2
    return weights + views + babbles + 400 * 2**20


_PAIR_BYTES = 4 * 2 * 32 * 8
"""Bytes of one recorded evaluation pair (eyes and head: two views of a few dozen angles)."""


def _check_memory(config: ICubConfig) -> None:
    """Before the frames check: one job and the main process's evaluation views fit in the
    memory available (:func:`sigmapi._memory.check`), else one line naming the sizes."""
    need = _job_memory(config) + 2 * config.eval_pairs * _PAIR_BYTES
    _memory.check(
        need,
        f"an icub run of grid={config.grid}, map_shape={config.map_shape}, "
        f"train_pairs={config.train_pairs:,}, eval_pairs={config.eval_pairs:,}, "
        f"babbles={config.babbles:,}",
        "lower --grid, --map-shape, --train-pairs, --eval-pairs or --babbles",
    )


ICUB = ICubExperiment()
register(ICUB)
"""The iCub experiment."""
