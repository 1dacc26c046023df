"""The reward experiment: does a map whose plasticity is gated by reward come to serve the task?

:data:`REWARD` runs a :class:`~sigmapi.experiments.reward.config.RewardConfig` on seeds and
returns a :class:`~sigmapi.experiments.reward.result.RewardResult`: per seed, one map learned
without a teacher, then the same actor-critic on three copies of it, ``frozen``, ``gated``
(:func:`~sigmapi.agents.gated.run_gated_episodes`) and ``shuffled`` (docs/guide/reward.md,
docs/algorithm.md "Reward-gated plasticity"), each map scored by :func:`map_scores`. Seed
``s``'s random streams are those of :data:`PLAN`, each a child of ``SeedSequence(s)``
(:mod:`sigmapi.experiments.kit.seeds`): ``"views"`` (the map's saccade views; the map is built
with seed ``s``), ``"starts"`` and ``"agent"`` (the same for every method), ``"probes"`` (the
test objects), ``"shuffle"`` and ``"fixations"`` (the gated updates' second fixations).

Examples
--------
>>> cfg = RewardConfig().replace(grid=5, map_shape=(5, 5), iterations=400, episodes=8,
...                              block=4, final_episodes=4, n_test=200)
>>> res = REWARD.run(cfg, seeds=[0])
>>> [m["name"] for m in res.to_dict()["methods"]]
['frozen', 'gated', 'shuffled']
"""

from __future__ import annotations

import copy
import functools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sigmapi.agents import actor_critic_for, run_episodes, run_gated_episodes
from sigmapi.codes import grid_coordinates
from sigmapi.envs import GazeReachEnv, MapObservation
from sigmapi.executor import job_memory
from sigmapi.experiments.base import register
from sigmapi.experiments.kit.jobs import SeedJob, SeedRuns, Tick
from sigmapi.experiments.kit.results import JSON
from sigmapi.experiments.kit.seeds import SeedPlan
from sigmapi.experiments.kit.worlds import GAZE_REACH, World
from sigmapi.experiments.reward.config import METHODS, RewardConfig
from sigmapi.experiments.reward.result import SCORES, RewardResult
from sigmapi.metrics import winner_metrics
from sigmapi.model.som import SigmaPiSOM

PLAN = SeedPlan({"views": 5, "starts": 6, "agent": 7, "probes": 8, "shuffle": 9, "fixations": 10})
"""The streams of a seed (:class:`~sigmapi.experiments.kit.seeds.SeedPlan`)."""


@dataclass(frozen=True)
class Probes:
    """Objects at random ``z`` ``(N, d)`` and two views of each (``x0, y0``, ``x1, y1``)."""

    z: NDArray[np.float64]
    views: tuple[NDArray[np.float64], ...]


def probe_objects(world: GazeReachEnv, n: int, rng: np.random.Generator) -> Probes:
    """``n`` objects uniform in the workspace, each seen from two random fixations."""
    z = rng.random((n, world.z_dim))
    x0, y0 = world.views_of(z, rng)
    x1, y1 = world.views_of(z, rng)
    return Probes(z, (x0, y0, x1, y1))


def preferred_z(model: SigmaPiSOM, objects: Probes) -> NDArray[np.float64]:
    """Each unit's preferred z ``(n_units, d)``: the mean z of the test objects whose first
    view it wins; NaN for a unit that wins none."""
    w = model.winner(objects.views[0], objects.views[1])
    counts = np.bincount(w, minlength=model.n_units).astype(np.float64)
    sums = np.zeros((model.n_units, objects.z.shape[1]))
    np.add.at(sums, w, objects.z)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(counts[:, None] > 0, sums / counts[:, None], np.nan)


def map_scores(
    model: SigmaPiSOM, objects: Probes, goal: NDArray[np.float64], near_radius: float
) -> dict[str, float]:
    """Magnification near the goal and the map's quality away from it.

    ``magnification``: (units whose :func:`preferred_z` lies in the box ``|z - goal|_inf <=
    near_radius``, over the box's area inside the workspace) / (units that win anything, over
    the workspace's area 1). 1 is a map that spends its units evenly; the area is that of the
    box clipped to ``[0, 1]^d``. ``units_near``: the count. ``view_consistency_away`` and
    ``order_r2_away``: :func:`~sigmapi.metrics.winner_metrics` on the objects outside the box
    (calibration on half of them, scores on the other half; NaN with fewer than 4 there).
    """
    pz = preferred_z(model, objects)
    used = np.all(np.isfinite(pz), axis=1)
    near_units = used & np.all(np.abs(np.nan_to_num(pz) - goal) <= near_radius, axis=1)
    area = float(np.prod(np.minimum(goal + near_radius, 1.0) - np.maximum(goal - near_radius, 0)))
    n_used = int(used.sum())
    mag = (near_units.sum() / area) / n_used if n_used else float("nan")
    away = np.any(np.abs(objects.z - goal) > near_radius, axis=1)
    m = {"view_consistency": float("nan"), "order_r2": float("nan")}
    if away.sum() >= 4:  # none away when the box covers the workspace
        z = objects.z[away]
        x0, y0, x1, y1 = (v[away] for v in objects.views)
        w0, w1 = model.winner(x0, y0), model.winner(x1, y1)
        half = len(z) // 2
        coords = grid_coordinates(tuple(model.map_shape))
        m = winner_metrics(w0[:half], z[:half], w0[half:], w1[half:], z[half:], coords, 1.0)
    return {
        "magnification": float(mag),
        "units_near": int(near_units.sum()),
        "units_used": n_used,
        "view_consistency_away": m["view_consistency"],
        "order_r2_away": m["order_r2"],
    }


class RewardExperiment(SeedRuns[RewardConfig]):
    """The frozen map, the reward-gated map and the shuffled-reward control, over seeds."""

    name = "reward"
    summary = "a map whose plasticity is gated by reward vs. the frozen map and a shuffled control"
    config_type = RewardConfig
    quick = RewardConfig().replace(
        episodes=100, block=25, final_episodes=25, iterations=4000, n_test=1000
    )
    seeds = (900, 901, 902, 903, 904, 905, 906, 907, 908, 909)
    """The seeds of the acceptance run (not the world's: none of them was tuned on)."""
    quick_seeds = (0,)
    quick_time = "about 30-60 s on two cores"
    default_out = "reward"

    def __init__(self, world: World = GAZE_REACH) -> None:
        self.world = world

    def check(self, config: RewardConfig) -> int:
        """One job's memory: the map's (:func:`~sigmapi.executor.job_memory`), its recorded
        views' positions (64 bytes an iteration) and the episodes' records (64 bytes each)."""
        som = config.som_config(0, self.world)
        views = 64 * som.iterations + 64 * config.run.episodes
        return job_memory(som, n_test=config.run.n_test) + views

    def steps(self, job: SeedJob) -> int:
        return len(job.config.run.methods) * job.config.run.episodes

    def seed_run(self, job: SeedJob, tick: Tick | None) -> JSON:
        """One seed: its map, then each method's learner on the same episodes, then the scores."""
        cfg, seed, world, run = job.config, job.seed, self.world, job.config.run
        learned = cfg.map.learn(world, cfg.env, seed, PLAN.rng(seed, "views"))
        place = world.source(cfg.env)
        objects = probe_objects(place, run.n_test, PLAN.rng(seed, "probes"))
        goal = np.asarray(place.goal, dtype=np.float64)

        def scored(model: SigmaPiSOM) -> JSON:  # a map's scores, its units' preferred z
            scores = map_scores(model, objects, goal, run.near_radius)
            return {"scores": scores, "units": preferred_z(model, objects)}

        out: JSON = {"initial": scored(learned), "runs": {}}
        features = (cfg.map.features, cfg.map.feature_width)
        gating = cfg.gate.gating()  # the same settings for every method
        factors: NDArray[np.float64] | None = None
        for m in sorted(run.methods, key=METHODS.index):
            model = copy.copy(learned)
            env = MapObservation(world.make_env(cfg.env), model, *features)
            agent = actor_critic_for(env, cfg.agent, seed=PLAN.rng(seed, "agent"))
            done = None if tick is None else functools.partial(tick, 1, m)
            starts = PLAN.rngs(seed, "starts", run.episodes)  # fresh: every method's the same
            updates = 0
            if m == "frozen":
                ep = run_episodes(env, agent, starts, on_episode=done)
            else:  # the shuffled run replays the gated one's factors (it came first)
                replay = None if factors is None else PLAN.rng(seed, "shuffle").permutation(factors)
                fixations = PLAN.rng(seed, "fixations")
                got = run_gated_episodes(
                    env, agent, starts, gating, fixations, surprises=replay, on_episode=done
                )
                ep, updates = got.episodes, got.updates
                factors = got.surprises if m == "gated" else factors
            out["runs"][m] = {"episodes": ep, "updates": updates, **scored(model)}
        return out

    def collect(
        self, config: RewardConfig, seeds: tuple[int, ...], per_seed: list[JSON]
    ) -> RewardResult:
        """The result of the per-seed values of the run (in the order of ``seeds``)."""
        res = RewardResult(config, seeds)
        for m in config.run.methods:
            runs = [v["runs"][m] for v in per_seed]
            res.record(m, [r["episodes"] for r in runs])
            res.updates[m] = np.array([r["updates"] for r in runs], dtype=np.int64)
            res.scores[m] = {k: np.array([r["scores"][k] for r in runs]) for k in SCORES}
            res.units[m] = runs[0]["units"]
        initial = [v["initial"] for v in per_seed]
        res.scores["initial"] = {k: np.array([i["scores"][k] for i in initial]) for k in SCORES}
        res.units["initial"] = initial[0]["units"]
        return res


REWARD = RewardExperiment()
register(REWARD)
"""The reward experiment."""
