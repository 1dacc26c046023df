"""The experiments' kit: the seed plan, the episode arithmetic, the map spec, the worlds, the
result base and its tables, configs of parts, report sections."""

from __future__ import annotations

import dataclasses
import json

import gymnasium as gym
import numpy as np
import pytest
from numpy.typing import NDArray

from sigmapi import load_preset
from sigmapi.agents import ActorCriticConfig
from sigmapi.envs import GazeReachConfig, GazeReachEnv
from sigmapi.errors import ConfigError
from sigmapi.experiments.kit.episodes import block_ends, block_rates, final_rates
from sigmapi.experiments.kit.maps import MapSpec
from sigmapi.experiments.kit.parts import Parts, parts_of
from sigmapi.experiments.kit.report import section_function
from sigmapi.experiments.kit.results import HEADERS, Column, Result, columns, plain, render
from sigmapi.experiments.kit.seeds import MODEL_KEYS, SeedPlan
from sigmapi.experiments.kit.worlds import WORLDS, World, get_world, register_world
from sigmapi.experiments.reach.config import MapConfig, ReachConfig, ReachRunConfig
from sigmapi.experiments.reach.run import REACH, ReachExperiment


def test_a_seed_plan_names_each_stream_a_child_of_the_seed_apart_from_a_models():
    from sigmapi.experiments.chain.run import PLAN as CHAIN
    from sigmapi.experiments.compare.run import PLAN as COMPARE
    from sigmapi.experiments.icub.run import PLAN as ICUB
    from sigmapi.experiments.neurons.run import PLAN as NEURONS
    from sigmapi.experiments.reach.run import PLAN as REACH
    from sigmapi.experiments.reward.run import PLAN as REWARD
    from sigmapi.experiments.robot.config import PLAN as ROBOT
    from sigmapi.experiments.stream.run import PLAN as STREAM

    def same(a: np.random.SeedSequence, b: np.random.SeedSequence) -> bool:
        return (a.entropy, a.spawn_key) == (b.entropy, b.spawn_key)

    plans = (CHAIN, COMPARE, ICUB, NEURONS, REACH, REWARD, ROBOT, STREAM)
    for plan in plans:  # one derivation: stream `name` of seed s is child (key,) of s
        for name, key in plan.keys.items():
            assert key not in MODEL_KEYS, name  # a model built with s draws under 0-4
            assert same(plan.sequence(9, name), np.random.SeedSequence(9, spawn_key=(key,)))
    reward = ("views", "starts", "agent", "probes", "shuffle", "fixations")
    assert [REWARD.keys[n] for n in reward] == [5, 6, 7, 8, 9, 10]
    assert [REACH.keys[n] for n in ("views", "starts", "agent")] == [5, 6, 7]
    assert same(STREAM.sequence(3, "frames", 16), np.random.SeedSequence(3, spawn_key=(7, 16)))
    assert same(CHAIN.sequence(3, "triples"), np.random.SeedSequence(3, spawn_key=(16,)))
    assert same(COMPARE.sequence(3, "data"), np.random.SeedSequence(3, spawn_key=(13,)))
    spikes = NEURONS.sequence(3, "spikes", 100, 5)  # the spike trains at 100 Hz, pool 5
    assert same(spikes, np.random.SeedSequence(3, spawn_key=(11, 100, 5)))
    a, b = REACH.rng(2, "starts").random(3), REACH.rng(2, "starts").random(3)
    np.testing.assert_array_equal(a, b)
    starts = REACH.rngs(2, "starts", 3)  # one generator per episode, each its own child
    assert all(isinstance(g, np.random.Generator) for g in starts)
    np.testing.assert_array_equal(starts[2].random(2), REACH.rng(2, "starts", 2).random(2))
    assert starts[0].random() != starts[1].random()
    with pytest.raises(ValueError, match="share a spawn key"):
        SeedPlan({"a": 5, "b": 5})
    with pytest.raises(ValueError, match=r"streams \['b'\] .* keys of a model of the seed \(0-4\)"):
        SeedPlan({"a": 5, "b": 4})
    with pytest.raises(KeyError):
        REACH.rng(0, "nope")


def test_an_episode_starts_from_a_generator_as_from_the_seed_it_stands_for():
    from sigmapi.agents import reset_from
    from sigmapi.experiments.kit.worlds import GAZE_REACH

    env = GAZE_REACH.make_env(GazeReachConfig(grid=7))
    by_seed, _ = env.reset(seed=12)
    by_rng, _ = reset_from(env, np.random.default_rng(12))  # Gymnasium's reset(seed=n)
    for k in by_seed:
        np.testing.assert_array_equal(by_seed[k], by_rng[k])
    gen = np.random.default_rng(5)
    reset_from(env, gen)
    assert env.unwrapped.np_random is gen  # the world draws from the generator handed to it
    env.close()


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
    sigma 3 -> 1 -> 0.5 and no refinement rounds (the run sets sizes, codes and length;
    without rounds it keeps the default draw of a round's pairs, which paper-2d changed)."""
    robot = load_preset("robot-2d")
    fixed = {"map_shape": (8, 8), "x_shape": (12, 12), "y_shape": (12, 12), "iterations": 40_000}
    before = load_preset("paper-2d").replace(
        sigma=((0.0, 3.0), (0.5, 1.0), (1.0, 0.5)), refine_rounds=0, refine_draw="random", **fixed
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


@dataclasses.dataclass
class _Toy(Result):
    """A result with a config, seeds, records and a summary computed from them."""

    config: GazeReachConfig
    seeds: tuple[int, ...]
    values: NDArray[np.float64] = dataclasses.field(default_factory=lambda: np.zeros(0))
    seconds: float = 0.0  # written (the summaries read back): the base's field

    KEYS = ("mean: mean_value", "values", "config: config_and_seeds", "seconds")
    COMPUTED = ("mean", "values")
    SEEDS_IN_CONFIG = True

    def mean_value(self) -> np.float64:
        return np.float64(np.nanmean(self.values))


def test_a_result_is_its_keys_in_order_as_json_and_reads_back_its_summaries():
    toy = _Toy(GazeReachConfig(grid=7), (3, 1), np.array([1.0, np.nan, 2.0]), 4.5)
    d = toy.to_dict()
    assert list(d) == ["mean", "values", "config", "seconds"]
    assert d["mean"] == 1.5 and type(d["mean"]) is float  # a numpy scalar as Python's
    assert d["values"] == [1.0, None, 2.0]  # NaN is no JSON number
    assert d["config"]["grid"] == 7 and d["config"]["seeds"] == [3, 1]
    back = _Toy.from_dict(json.loads(json.dumps(d)))
    assert back.config == toy.config and back.seeds == (3, 1) and back.seconds == 4.5
    assert back.written == {"mean": 1.5, "values": [1.0, None, 2.0]}
    assert back.to_dict() == d  # to_dict -> from_dict -> to_dict is the identity
    with pytest.raises(KeyError, match="values"):  # a computed key the file lacks
        _Toy.from_dict({k: v for k, v in d.items() if k != "values"})
    with pytest.raises(TypeError, match="JSON object"):
        _Toy.from_dict([d])
    with pytest.raises(ConfigError, match="distinct"):
        _Toy.from_dict({**d, "config": {**d["config"], "seeds": [1, 1]}})
    assert plain({"a": (np.int64(2), np.array([[1, 2]]))}) == {"a": [2, [[1, 2]]]}


def test_a_table_is_its_columns_header_and_cells_aligned_by_their_spec():
    cols = (
        Column("name", "name", "6s"),
        Column("score", "score", "7.3f"),
        Column("n", lambda r: r["n"] * 2, ">4"),
    )
    lines = render(
        cols, [{"name": "ab", "score": 0.5, "n": 3}, {"name": "c", "score": None, "n": 1}]
    )
    assert lines == ["name     score    n", "ab       0.500    6", "c            -    2"]


def test_columns_from_key_format_words_head_shared_keys_once():
    extra = Column("n", "n", ">3")
    cols = columns("name:8s z_error:7.3f", "z_error_worst:6.3f seed:<5d", extra, seed="run")
    assert [(c.name, c.key, c.format) for c in cols[:4]] == [
        (HEADERS["name"], "name", "8s"),
        ("z error", "z_error", "7.3f"),
        ("worst", "z_error_worst", "6.3f"),
        ("run", "seed", "<5d"),
    ]
    assert cols[4] is extra
    row = {"name": "pairs", "z_error": 0.25, "z_error_worst": 0.5, "seed": 3, "n": 7}
    assert render(cols, [row]) == [
        "method   z error  worst run     n",
        "pairs      0.250  0.500 3       7",
    ]


def test_a_config_of_parts_derives_its_parts_from_its_fields():
    assert ReachConfig.PARTS == {
        "env": GazeReachConfig,
        "map": MapConfig,
        "agent": ActorCriticConfig,
        "run": ReachRunConfig,
    }
    assert parts_of(ReachConfig) == ReachConfig.PARTS and parts_of(GazeReachConfig) == {}
    cfg = ReachConfig().replace(grid=7, episodes=300)
    assert (cfg.env.grid, cfg.run.episodes) == (7, 300)
    assert ReachConfig.from_dict(cfg.to_dict()) == cfg
    with pytest.raises(ConfigError, match="unknown reach config field 'nope'"):
        cfg.replace(nope=1)
    with pytest.raises(TypeError, match="must be a dataclass"):

        @dataclasses.dataclass(frozen=True)
        class Bad(Parts):
            env: int = 0


def test_a_report_section_is_named_by_module_and_function():
    from sigmapi.experiments.reach.section import reach_section

    assert section_function("sigmapi.experiments.reach.section:reach_section") is reach_section
    assert section_function(reach_section) is reach_section
    with pytest.raises(ConfigError, match="'module:function'"):
        section_function("reach_section")
