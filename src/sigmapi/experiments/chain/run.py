"""A chain of frames: two Sigma-Pi maps in a row against one map on the whole transformation.

Retinal position x, eye-in-head angle e and head-on-body angle u in [0, 1]; head-centred
``a = (x + e) / 2``, body-centred ``z = (a + u) / 2``. **The chain**: map A (retina + eye ->
head) trained on its built-in task hands its code (:func:`head_code`) to map B (A's code + head
-> body), trained on view pairs of triples with the same z. **The single map**: one map of
third-order units on the retina and the joint code of (e, u) (:func:`single_config`), trained
on the same triples with B's config but for the grids. Both routes are scored by
:func:`~sigmapi.metrics.winner_metrics` on the same calibration and test triples from the
fixed evaluation seed, beside their cost (weights, training seconds). The definitions:
docs/algorithm.md, "A chain of frames".

Read top to bottom: the settings (:class:`ChainConfig`), the result (:class:`ChainResult`)
and the run (:class:`Chain`, one job per seed; :func:`run_chain` from Python, any config).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Any, Literal, NamedTuple, get_args

import numpy as np
from numpy.typing import NDArray

from sigmapi import _memory, _validate
from sigmapi.codes import PopulationCode
from sigmapi.config import SOMConfig
from sigmapi.errors import ConfigError
from sigmapi.executor import Executor, job_memory
from sigmapi.experiments.base import KEY_VALUES, Run, check_seeds, register
from sigmapi.experiments.kit.jobs import SeedJob, SeedRuns, Tick, iterations_counted
from sigmapi.experiments.kit.maps import MapSpec
from sigmapi.experiments.kit.results import Result, as_object, columns, render
from sigmapi.experiments.kit.seeds import SeedPlan
from sigmapi.metrics import EVAL_SEED, evaluate, winner_metrics
from sigmapi.model.som import SigmaPiSOM
from sigmapi.progress import Progress
from sigmapi.tasks import TwoViewSampler

# -- the settings ----------------------------------------------------------------------------------


Code = Literal["response", "winner"]


CODES: tuple[str, ...] = get_args(Code)
"""What map A hands to map B: its normalised response, or a code of its winner's position."""


def chain_config(config: SOMConfig | None = None, iterations: int | None = None) -> SOMConfig:
    """The config every map of the comparison starts from (default: paper-1d, unrefined).

    It must be 1-D (``map_shape``, ``x_shape`` and ``y_shape`` of one axis), non-periodic,
    with the ``mean`` relation; map A uses it as it is.
    """
    unrefined = MapSpec("paper-1d", changes={"refine_rounds": 0})
    cfg = config if config is not None else unrefined.config()
    if not isinstance(cfg, SOMConfig):
        fix = "load a preset with sigmapi.load_preset(name)"
        raise _validate.fail("config", "a sigmapi.SOMConfig or None", type(cfg).__name__, fix)
    for name in ("map_shape", "x_shape", "y_shape"):
        if len(getattr(cfg, name)) != 1:
            fix = "the chain of frames is built on 1-D positions, e.g. (15,)"
            raise _validate.fail(f"config.{name}", "1-D (one axis)", getattr(cfg, name), fix)
    if cfg.periodic or cfg.relation != "mean":
        raise ConfigError(
            f"config must be non-periodic with relation 'mean', got periodic={cfg.periodic}, "
            f"relation={cfg.relation!r}; the chain composes two means: a = (x + e) / 2, "
            "z = (a + u) / 2"
        )
    if iterations is not None:
        cfg = cfg.replace(iterations=_validate.integer("iterations", iterations, 1))
    return cfg


@dataclass(frozen=True)
class ChainConfig:
    """What ``sigmapi chain`` trains: the preset of every map and the data of maps B and single."""

    preset: str = "paper-1d"
    """The 1-D preset every map starts from (``sigmapi presets``), with sigmapi's ordering
    procedure (``crossview``) and no refinement (``refine_rounds=0``, the setting
    docs/results/chain.md measures; an override can turn it on)."""
    overrides: tuple[str, ...] = field(default=(), metadata=KEY_VALUES)
    """``key=value`` changes to the preset, e.g. ``iterations=50000`` (one per change)."""
    train_pairs: int = field(
        default=20_000, metadata=_validate.bounded("int", 10, 10_000_000, fix="e.g. 20000")
    )
    """View pairs of triples that map B and the single map are trained on."""
    n_test: int = field(
        default=10_000, metadata=_validate.bounded("int", 10, 1_000_000, fix="e.g. 10000")
    )
    """Calibration and test triples (each), from the fixed evaluation seed."""
    code: Code = "response"
    """What map A hands to map B: its normalised response, or a code of its winner's position."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "overrides", tuple(self.overrides))
        _validate.check_fields(self)
        _validate.choice("code", self.code, CODES)
        self.som_config  # noqa: B018 (an unknown preset or a bad override fails here, not later)

    @property
    def som_config(self) -> SOMConfig:
        """The preset with ``ordering="crossview"``, ``refine_rounds=0`` and the overrides
        (:func:`chain_config`)."""
        spec = MapSpec(self.preset, self.overrides, {"ordering": "crossview", "refine_rounds": 0})
        return chain_config(spec.config())


@dataclass(frozen=True)
class ChainSettings:
    """What the chain's jobs read of a :class:`ChainConfig`, with any map config in place of
    a preset and its overrides (:func:`run_chain`'s)."""

    som_config: SOMConfig
    """Every map's config."""
    train_pairs: int
    """View pairs of triples that map B and the single map are trained on."""
    n_test: int
    """Calibration and test triples (each)."""
    code: str
    """What map A hands to map B (:data:`CODES`)."""


# -- the result: its JSON form, summary and table --------------------------------------------------


TARGET_RATIO = 2.0
"""The acceptance bound of the chain of frames: the chain's z error at most this many times
the single map's."""


SUMMARY_KEYS = ("z_error", "view_consistency", "order_r2", "usage", "weights", "train_seconds")
"""The scores summarised per route (medians over seeds)."""

ROUTES = ("chain", "single")

COLUMNS = columns(
    "seed:<5d route:7s z_error:7.3f view_consistency:12.3f order_r2:10.3f usage:6.2f",
    "weights:8d train_seconds:8.1f",
    view_consistency="same winner",
)
"""The table's columns: one row per seed and route."""


@dataclass
class ChainResult(Result):
    """Both routes per seed (:meth:`Chain.seed_run`) and the settings they ran with."""

    config: SOMConfig
    train_pairs: int
    n_test: int
    code: str
    per_seed: list[dict[str, Any]]

    KEYS = ("settings", "seeds: per_seed", "summary")
    """The JSON form: the settings, one dict per seed and the summary."""

    @classmethod
    def from_dict(cls, data: object) -> ChainResult:
        """The result that :meth:`to_dict` wrote (``result.json``)."""
        obj = as_object(data)
        st, config = obj["settings"], SOMConfig.from_dict(obj["settings"]["config"])
        return cls(config, st["train_pairs"], st["n_test"], st["code"], list(obj["seeds"]))

    def summary(self) -> dict[str, object]:
        """The medians of both routes, the median and worst ratio and how many seeds meet
        ``ratio <= TARGET_RATIO``."""
        per_seed = self.per_seed

        def med(route: str, key: str) -> float:
            return float(np.median([r[route][key] for r in per_seed]))

        ratios = [r["ratio"] for r in per_seed]
        out: dict[str, object] = {r: {k: med(r, k) for k in SUMMARY_KEYS} for r in ROUTES}
        out.update(
            ratio_median=float(np.median(ratios)),
            ratio_worst=float(max(ratios)),
            met=int(sum(r <= TARGET_RATIO for r in ratios)),
            n_seeds=len(per_seed),
            target_ratio=TARGET_RATIO,
            map_a_order_r2_min=min(r["map_a"]["order_r2"] for r in per_seed),
        )
        return out

    def settings(self) -> dict[str, object]:
        """The map config, the training pairs, test points, code and the seeds."""
        given = {k: getattr(self, k) for k in ("config", "train_pairs", "n_test", "code")}
        return {**given, "seeds": [r["seed"] for r in self.per_seed]}

    def table(self) -> str:
        """Both routes per seed, then the summary line."""
        rows = [{"seed": r["seed"], "route": k, **r[k]} for r in self.per_seed for k in ROUTES]
        s = self.summary()
        met = f"{s['met']} of {s['n_seeds']} seeds: chain z error <= {s['target_ratio']:g} x"
        ratio = f"(median ratio {s['ratio_median']:.2f}, worst {s['ratio_worst']:.2f})"
        return "\n".join([*render(COLUMNS, rows), f"{met} the single map's {ratio}"])


Array = NDArray[np.float64]


# -- the run: the triples, both routes per seed, the experiment ------------------------------------


PLAN = SeedPlan({"triples": 16})
"""The streams of a seed (:class:`~sigmapi.experiments.kit.seeds.SeedPlan`): the training
triples, ``SeedSequence(seed, spawn_key=(16,))``, apart from the streams a model of the same
seed draws (:data:`~sigmapi.experiments.kit.seeds.MODEL_KEYS`)."""


class Triples(NamedTuple):
    """Two views (x, e, u) of each of ``n`` body-centred positions z; every array ``(n, 1)``."""

    x0: Array
    e0: Array
    u0: Array
    x1: Array
    e1: Array
    u1: Array
    z: Array

    def view(self, v: int) -> tuple[Array, Array, Array]:
        """``(x, e, u)`` of view ``v`` (0 or 1)."""
        return (self.x0, self.e0, self.u0) if v == 0 else (self.x1, self.e1, self.u1)


_MEAN = TwoViewSampler("mean", PopulationCode((2,)), PopulationCode((2,)))
"""The paper's relation; only its view sampler is used (the codes are not)."""


def sample_triples(n: int, rng: np.random.Generator) -> Triples:
    """``n`` body-centred positions z, uniform in [0, 1], with two views (x, e, u) of each.

    Each view: (a, u) with ``(a + u) / 2 = z``, then (x, e) with ``(x + e) / 2 = a``, both
    drawn as the paper's task draws a view (:meth:`~sigmapi.tasks.TwoViewSampler.sample_view`).

    Examples
    --------
    >>> t = sample_triples(5, np.random.default_rng(0))
    >>> bool(np.allclose(((t.x1 + t.e1) / 2 + t.u1) / 2, t.z)), t.z.shape
    (True, (5, 1))
    """
    _validate.integer("n", n, 1)
    z = rng.uniform(0.0, 1.0, (n, 1))
    views: list[Array] = []
    for _ in range(2):
        a, u = _MEAN.sample_view(z, rng)
        x, e = _MEAN.sample_view(a, rng)
        views += [x, e, u]
    x0, e0, u0, x1, e1, u1 = views
    return Triples(x0, e0, u0, x1, e1, u1, z)


def head_code(model_a: SigmaPiSOM, x: Array, e: Array, code: str = "response") -> Array:
    """Map A's output for retinal positions ``x`` and eye angles ``e`` ``(B, 1)``: ``(B, n_a)``.

    ``"response"``: A's activations, rectified and scaled to length 1 (as the input codes
    are); ``"winner"``: the population code (the input codes' width) of the hard winner's
    position as a fraction of A's map.
    """
    _validate.choice("code", code, CODES)
    xc, ec = model_a.x_code.encode(x), model_a.y_code.encode(e)
    if code == "winner":
        n = model_a.map_shape[0]
        k = model_a.winner(xc, ec, hard=True)
        pos = k[:, None] / max(n - 1, 1)
        return PopulationCode(model_a.map_shape, model_a.config.code_width).encode(pos)
    h = np.maximum(model_a.respond(xc, ec), 0.0)
    norm = np.linalg.norm(h, axis=1, keepdims=True)
    return np.asarray(h / np.where(norm > 0, norm, 1.0))


def single_config(cfg: SOMConfig) -> SOMConfig:
    """The single map's config: ``cfg`` with the retina on a ``(n_x, 1)`` grid and the joint
    ``(n_e, n_u)`` grid of eye and head angles."""
    return cfg.replace(x_shape=(cfg.x_shape[0], 1), y_shape=(*cfg.y_shape, *cfg.y_shape))


def _single_inputs(model: SigmaPiSOM, t: Triples, v: int) -> tuple[Array, Array]:
    """The single map's codes of view ``v``: x on its ``(n_x, 1)`` grid, (e, u) jointly."""
    x, e, u = t.view(v)
    retina = np.hstack([x, np.zeros_like(x)])
    return model.x_code.encode(retina), model.y_code.encode(np.hstack([e, u]))


def run_chain(
    seeds: Sequence[int] = (0, 1, 2),
    *,
    config: SOMConfig | None = None,
    iterations: int | None = None,
    train_pairs: int = 20_000,
    n_test: int = 10_000,
    code: str = "response",
    executor: Executor | None = None,
    progress: Progress | None = None,
) -> dict[str, object]:
    """The chain of frames against the single map, per seed and summarised.

    Parameters
    ----------
    seeds : sequence of int
        Each seed draws its own training triples and seeds all three maps.
    config : SOMConfig, optional
        Settings of every map (default: paper-1d with ``ordering="crossview"``); 1-D, the
        ``mean`` relation (:func:`chain_config`). Map B and the single map change only grids.
    iterations : int, optional
        Iterations of each of the three maps (default: ``config.iterations``).
    train_pairs, n_test, code : int, int, {"response", "winner"}
        As :class:`ChainConfig` has them (map A trains on its built-in task, :func:`head_code`).
    executor : Executor, optional
        Where the seeds run (None: one after another in this process).
    progress : Progress, optional
        A line or bar per finished seed on stderr (None: nothing).

    Returns
    -------
    dict
        :meth:`ChainResult.to_dict`: ``"settings"``; ``"seeds"``, per seed ``"map_a"`` (its
        own :func:`~sigmapi.metrics.evaluate`), the scores and costs of ``"chain"`` and
        ``"single"`` and ``"ratio"`` (chain z error / single z error); ``"summary"``.
    """
    cfg = chain_config(config, iterations)
    seeds = check_seeds(seeds)
    _validate.integer("train_pairs", train_pairs, 10, fix="e.g. 20000")
    _validate.integer("n_test", n_test, 10, fix="e.g. 10000")
    _validate.choice("code", code, CODES)
    given = ChainSettings(cfg, train_pairs, n_test, code)
    return CHAIN.execute(given, Run(seeds, executor=executor, progress=progress)).to_dict()


QUICK = ChainConfig(overrides=("iterations=60000",), train_pairs=5000, n_test=2000)
"""The quick chain (``sigmapi chain --quick``): every map at paper-1d's quick length (as in
``sigmapi reproduce --quick``), less data; a first look, not the measured setting."""


class Chain(SeedRuns[Any]):
    """Train map A (retina + eye -> head-centred) on its task, map B (A's response + head ->
    body-centred) and one third-order map on the whole transformation on the same triples, and
    score both routes by the same metrics."""

    name = "chain"
    summary = "a chain of two maps (retina -> head -> body) against one map on the whole task"
    config_type = ChainConfig
    seeds = (0, 1, 2)
    quick = QUICK
    quick_seeds = (0,)
    quick_time = "about 15 s on two cores"
    unit = "it"

    def check(self, config: ChainConfig) -> int:
        """Refuse data that does not fit; one job's memory (maps A and B and the single map)."""
        cfg, pairs, n_test = config.som_config, config.train_pairs, config.n_test
        width = 8 * 3 * (int(np.prod(cfg.x_shape)) + int(np.prod(cfg.y_shape)))  # a triple
        _memory.check_count("train_pairs", pairs, 2 * width, "e.g. --train-pairs 20000")
        _memory.check_count("n_test", n_test, 4 * width, "e.g. --n-test 10000")
        return 2 * job_memory(cfg, n_test) + job_memory(single_config(cfg), n_test)

    def prepare(self, config: ChainConfig, progress: object) -> tuple[SOMConfig, Triples, Triples]:
        """The map config and the calibration and test triples, from the fixed evaluation seed."""
        evaluation = np.random.SeedSequence(EVAL_SEED).spawn(2)  # calibration, test
        cal, test = (sample_triples(config.n_test, np.random.default_rng(s)) for s in evaluation)
        return config.som_config, cal, test

    def steps(self, job: SeedJob) -> int:
        return 3 * job.shared[0].iterations

    def describe(self, key: str, value: dict[str, Any]) -> str:
        chain, single = value["chain"]["z_error"], value["single"]["z_error"]
        return f"seed {key}: chain z error {chain:.3f}, single {single:.3f}"

    def seed_run(self, job: SeedJob, tick: Tick | None) -> dict[str, object]:
        """Train map A, map B and the single map on seed ``job.seed``'s triples and score both
        routes on the shared calibration and test triples (one entry of ``"seeds"``)."""
        seed, code, (cfg, cal, test) = job.seed, job.config.code, job.shared
        train = sample_triples(job.config.train_pairs, PLAN.rng(seed, "triples"))
        spacing = float(cfg.y_shape[0] - 1)

        def both(inputs: Callable[..., tuple[Array, Array]]) -> tuple[Array, Array, Array, Array]:
            return (*inputs(train, 0), *inputs(train, 1))  # the training triples' view pairs

        # the chain: A on its own task, then B on A's code of the triples' views and the head code
        start = time.perf_counter()
        its = cfg.iterations
        a = SigmaPiSOM(cfg, seed=seed).fit(callback=iterations_counted(tick, "map A", its))
        b = SigmaPiSOM(cfg.replace(x_shape=a.map_shape), seed=seed)

        def chain_inputs(t: Triples, v: int) -> tuple[Array, Array]:
            x, e, u = t.view(v)
            return head_code(a, x, e, code), b.y_code.encode(u)

        b.fit(both(chain_inputs), callback=iterations_counted(tick, "map B", its))
        chain_seconds = time.perf_counter() - start

        # the single map on the whole transformation: same triples, same config but the grids
        start = time.perf_counter()
        s = SigmaPiSOM(single_config(cfg), seed=seed)
        single_inputs = partial(_single_inputs, s)
        s.fit(both(single_inputs), callback=iterations_counted(tick, "single map", its))
        if tick is not None:
            tick(0, "scoring both routes")
        single_seconds = time.perf_counter() - start

        out: dict[str, Any] = {"seed": seed}
        m_a = evaluate(a)
        out["map_a"] = {k: getattr(m_a, k) for k in ("z_error", "view_consistency", "order_r2")}
        views = ((cal, 0), (test, 0), (test, 1))  # the calibration's first view, both test views
        for name, model, inputs, weights, secs in (
            ("chain", b, chain_inputs, a.weights_.size + b.weights_.size, chain_seconds),
            ("single", s, single_inputs, s.weights_.size, single_seconds),
        ):
            w = [model.winner(*inputs(t, v), hard=True) for t, v in views]
            scores = winner_metrics(w[0], cal.z, w[1], w[2], test.z, model.map_coords, spacing)
            out[name] = {**scores, "weights": int(weights), "train_seconds": secs}
        out["ratio"] = out["chain"]["z_error"] / out["single"]["z_error"]
        return out

    def collect(
        self, config: ChainConfig, seeds: tuple[int, ...], values: list[Any]
    ) -> ChainResult:
        c = config
        return ChainResult(c.som_config, c.train_pairs, c.n_test, c.code, values)


CHAIN = Chain()
register(CHAIN)
