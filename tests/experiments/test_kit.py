"""The experiments' kit: the seed plan, the episode arithmetic, the map spec, the worlds."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from sigmapi import load_preset
from sigmapi.envs import GazeReachConfig, GazeReachEnv
from sigmapi.errors import ConfigError
from sigmapi.experiments.kit.episodes import block_ends, block_rates, final_rates
from sigmapi.experiments.kit.maps import MapSpec
from sigmapi.experiments.kit.seeds import SeedPlan
from sigmapi.experiments.kit.worlds import WORLDS, World, get_world, register_world
from sigmapi.experiments.reach.config import ReachConfig
from sigmapi.experiments.reach.run import REACH, ReachExperiment


def test_a_seed_plan_names_the_streams_each_experiment_drew_before():
    from sigmapi.experiments.chain.run import PLAN as CHAIN
    from sigmapi.experiments.compare.run import PLAN as COMPARE
    from sigmapi.experiments.reach.run import PLAN as REACH
    from sigmapi.experiments.reward.run import PLAN as REWARD
    from sigmapi.experiments.robot.config import PLAN as ROBOT
    from sigmapi.experiments.stream.run import PLAN as STREAM

    def same(a: np.random.SeedSequence, b: np.random.SeedSequence) -> bool:
        return (a.entropy, a.spawn_key) == (b.entropy, b.spawn_key)

    root = np.random.SeedSequence(0)  # reach and reward: seed s is child s of the root 0
    reward = ("map", "starts", "agent", "probes", "shuffle", "fixations")
    for plan, names in ((REACH, ("map", "starts", "agent")), (REWARD, reward)):
        for k, name in enumerate(names):
            child = np.random.SeedSequence(root.entropy, spawn_key=(5, k))
            assert same(plan.sequence(5, name), child), name
    for k, name in enumerate(("map", "starts", "agent", "film")):  # robot: the seed's children
        assert same(ROBOT.sequence(9, name), np.random.SeedSequence(9, spawn_key=(k,)))
    assert same(STREAM.sequence(3, "frames", 16), np.random.SeedSequence(3, spawn_key=(7, 16)))
    assert same(CHAIN.sequence(3, "triples"), np.random.SeedSequence(3, spawn_key=(16,)))
    assert same(COMPARE.sequence(3, "data"), np.random.SeedSequence(3, spawn_key=(13,)))
    a, b = REACH.rng(2, "starts").random(3), REACH.rng(2, "starts").random(3)
    np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match="share a spawn key"):
        SeedPlan({"a": 1, "b": 1})
    with pytest.raises(KeyError):
        REACH.rng(0, "nope")


def test_block_and_final_rates():
    outcomes = np.array([[1, 0, 1, 1, 0, 0, 1], [0, 0, 1, 1, 1, 1, 0]], dtype=bool)
    rates = block_rates(outcomes, 3)  # the 7th episode is in no block
    np.testing.assert_array_equal(rates, [[2 / 3, 1 / 3], [1 / 3, 1.0]])
    np.testing.assert_array_equal(block_ends(rates.shape[1], 3), [3.0, 6.0])
    np.testing.assert_array_equal(final_rates(outcomes, 2), [0.5, 0.5])
    assert block_rates(outcomes, 8).shape == (2, 0)


def test_a_map_spec_applies_changes_then_overrides_then_the_fixed_fields():
    spec = MapSpec("paper-1d", ("iterations=5000", "refine_rounds=2"), {"refine_rounds": 0})
    cfg = spec.config(seed=4, backend="reference")
    assert (cfg.iterations, cfg.refine_rounds, cfg.seed, cfg.backend) == (5000, 2, 4, "reference")
    assert MapSpec("paper-1d").config() == load_preset("paper-1d")


def test_the_robot_preset_is_paper_2d_with_the_robots_schedule():
    """What the robot experiment trained before its schedule became a preset: paper-2d with
    sigma 3 -> 1 -> 0.5 and no refinement rounds (the run sets sizes, codes and length)."""
    robot = load_preset("robot-2d")
    fixed = {"map_shape": (8, 8), "x_shape": (12, 12), "y_shape": (12, 12), "iterations": 40_000}
    before = load_preset("paper-2d").replace(
        sigma=((0.0, 3.0), (0.5, 1.0), (1.0, 0.5)), refine_rounds=0, **fixed
    )
    got, want = robot.to_dict(), before.to_dict()
    got.pop("extra"), want.pop("extra")
    assert got == want


class OffCentreReach(GazeReachEnv):
    """A world no experiment knew: the gaze-and-reach world with its goal at 0.25."""

    def __init__(self, **kwargs):
        super().__init__(goal=0.25, **kwargs)


def _toy_kwargs(settings):
    return {**settings.env_kwargs(), "max_episode_steps": settings.max_episode_steps}


def _toy_source(settings):
    return OffCentreReach(**settings.env_kwargs())


def test_a_new_world_is_one_entry_and_reach_runs_on_it():
    toy_id = "sigmapi-test/OffCentreReach-v0"
    gym.register(id=toy_id, entry_point=OffCentreReach)
    try:
        with pytest.raises(ConfigError, match="unknown world 'off-centre'"):
            get_world("off-centre")
        toy = register_world(World("off-centre", toy_id, GazeReachConfig, _toy_kwargs,
                                   _toy_source, MapSpec("paper-2d"), (7, 8)))  # fmt: skip
        assert get_world("off-centre") is toy
        experiment = ReachExperiment(toy)
        assert experiment.default_seeds(ReachConfig()) == (7, 8)  # the world's
        cfg = ReachConfig().replace(dim=1, grid=7, map_shape=(6,), iterations=300, episodes=12,
                                    block=6, final_episodes=6, max_episode_steps=25,
                                    backend="reference")  # fmt: skip
        assert isinstance(toy.make_env(cfg.env).unwrapped, OffCentreReach)
        here = experiment.run(cfg, seeds=[0]).to_dict()
        there = REACH.run(cfg, seeds=[0]).to_dict()
        assert set(here["success"]) == set(there["success"]) == {"map", "retina", "retina_gaze",
                                                                   "true_z"}  # fmt: skip
        assert here["curves"] != there["curves"]  # another goal, other episodes
        with pytest.raises(ConfigError, match="settings of world 'off-centre'"):
            toy.make_env(object())
    finally:
        WORLDS.pop("off-centre", None)
        gym.registry.pop(toy_id, None)


def test_worlds_map_specs_and_seed_plans_travel_to_other_processes():
    import pickle

    from sigmapi.experiments.kit.worlds import GAZE_REACH
    from sigmapi.experiments.robot.config import PLAN, ROBOT_WORLD

    for value in (GAZE_REACH, ROBOT_WORLD, PLAN, MapSpec("paper-1d", changes={"eps": 0.1})):
        assert pickle.loads(pickle.dumps(value)) == value


def test_declared_bounds_are_checked_by_one_validator_and_shown_by_help():
    from dataclasses import dataclass, field

    from sigmapi import _validate
    from sigmapi.cli import build_parser

    @dataclass(frozen=True)
    class Cfg:
        n: int = field(default=3, metadata=_validate.bounded("int", 1, fix="e.g. 3"))
        share: float = field(default=0.5, metadata=_validate.bounded("number", 0, 1, lo_open=True))

        def __post_init__(self):
            _validate.check_fields(self)

    assert Cfg(n=np.int64(4)).n == 4 and type(Cfg(n=np.int64(4)).n) is int
    with pytest.raises(ConfigError, match=r"^n must be an int >= 1, got 0; e.g. 3$"):
        Cfg(n=0)
    with pytest.raises(ConfigError, match=r"share must be a number in \(0, 1\], got 0"):
        Cfg(share=0)
    with pytest.raises(ConfigError, match=r"episodes must be an int in \[1, 1000000\]"):
        ReachConfig().replace(episodes=0)
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    text = " ".join(sub.choices["reach"].format_help().split())
    assert "(an int in [1, 1000000]; default 600)" in text  # --episodes
    assert "(a number in (0, 1]; default 0.05)" in text  # --plateau-rise
    robot = " ".join(sub.choices["robot"].format_help().split())
    assert "(a number in [0, 1]; default 0.0)" in robot  # --moved-share
