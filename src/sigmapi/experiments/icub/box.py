"""``sigmapi icub --space box``: the 3-D task run on seeds, its result, JSON and table.

One job per seed (:func:`~sigmapi.experiments.icub.reach3d.run_seed3d`): the 3-D maps
recorded from both eyes' pixels, learned and scored against the true positions; babbling;
the associations; the reaches with the eyes free and after a fixation. :class:`ICubBoxResult`
pools the seeds: per map the median scores, per method the end-point error (median and 90th
percentile over every reach of every seed) and the strict success, and the task's targets
(:data:`TARGETS3D`).
"""

from __future__ import annotations

import resource
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from sigmapi.executor import Executor
from sigmapi.experiments.base import run_all
from sigmapi.experiments.icub import space3d as s3
from sigmapi.experiments.icub.config import ICubConfig
from sigmapi.experiments.icub.reach3d import METHODS, REACHABLE, run_seed3d
from sigmapi.experiments.kit.results import Result, check_records
from sigmapi.metrics import ORDERED_R2
from sigmapi.progress import Progress

TARGETS3D: dict[str, float] = {
    "learned_end_point_cm": 2.0,
    "learned_end_point_over_true": 1.5,
    "learned_strict_success": 0.9,
    "random_posture_strict_success": 0.15,
    "learned_minus_retina": 0.3,
    "order_r2_per_axis": ORDERED_R2,
    "map_error_ratio_to_kmeans": 1.5,
}
"""The bounds of the 3-D task's targets (eyes free; docs/guide/icub-3d.md):
``learned_end_point_cm`` and ``learned_end_point_over_true`` (the learned chain's median
end-point error, and over the true position's), the strict successes (the learned chain's
at least, a random posture's at most, the learned chain's over the retina's by at least),
every map's order per axis and its error over k-means'."""


def _peak_mb() -> float:
    """This process's peak resident memory, MB (``ru_maxrss``: KiB on Linux, bytes on macOS)."""
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / 2**20 if sys.platform == "darwin" else peak / 1024


@dataclass(frozen=True)
class _BoxJob:
    config: ICubConfig
    seed: int
    film: bool = False
    """The first seed: also the film and the eyes' frames for the figures."""


def _box_seed(job: _BoxJob) -> dict[str, Any]:
    """One seed of the 3-D task, its raw reaches kept as lists (for the pooled numbers)."""
    cfg = job.config
    out = run_seed3d(
        job.seed,
        pairs=cfg.box_pairs,
        eval_pairs=cfg.box_eval_pairs,
        iterations=cfg.box_iterations,
        babbles=cfg.box_babbles,
        epochs=cfg.epochs,
        reaches=cfg.reaches,
        feature_width=cfg.box_feature_width,
        restarts=cfg.box_restarts,
        balls=cfg.box_balls,
        babbling=cfg.box_babbling,
        yaw=cfg.babble_yaw,
        wrist=(cfg.babble_wrist[0], cfg.babble_wrist[1]),
        backend=cfg.backend,
        keep=True,
        film=job.film,
    )
    tests = out.pop("tests")
    for key, raw in (
        ("end_point_m", tests.end_point),
        ("aim_m", tests.aim),
        ("strict", tests.strict),
        ("touched", tests.touched),
    ):
        out[key] = {c: {m: v.tolist() for m, v in d.items()} for c, d in raw.items()}
    out["ik_error_m"] = tests.ik_error.tolist()
    out["peak_rss_mb"] = _peak_mb()
    return out


def _map_weights() -> tuple[int, int]:
    """The weights of map H and of map T as
    :func:`~sigmapi.experiments.icub.space3d.learn_chain3d` builds them by default
    (:data:`~sigmapi.experiments.icub.space3d.DESIGN`: one 1-D map per axis on two codes): map H
    (:data:`~sigmapi.experiments.icub.space3d.HEAD_SHAPE`) on codes of
    :data:`~sigmapi.experiments.icub.space3d.GRID` units (column and version, row and tilt)
    and :data:`~sigmapi.experiments.icub.space3d.DEPTH_GRID` (disparity and vergence), map T
    (:data:`~sigmapi.experiments.icub.space3d.TORSO_SHAPE`) on codes of
    :data:`~sigmapi.experiments.icub.space3d.TORSO_GRID` units."""
    head_codes = (s3.GRID, s3.GRID, s3.DEPTH_GRID)
    head = sum(u * c * c for u, c in zip(s3.HEAD_SHAPE, head_codes, strict=True))
    torso = sum(u * s3.TORSO_GRID**2 for u in s3.TORSO_SHAPE)
    return head, torso


def _job_memory() -> int:
    """Bytes of one job, an upper estimate that schedules the jobs: the maps' weights
    (:func:`_map_weights`, map T's once per fit, at most
    :data:`~sigmapi.experiments.icub.space3d.MAX_RESTARTS`) in float64 three times over (the
    weights, the trainer's state, a copy), and :data:`_JOB_REST` for the rest (the measured
    peak: docs/guide/icub-3d.md)."""
    head, torso = _map_weights()
    return (head + s3.MAX_RESTARTS * torso) * 8 * 3 + _JOB_REST


_JOB_REST = 768 * 2**20
"""Bytes of one job besides the maps' weights (:func:`_job_memory`): the interpreter with
NumPy and MuJoCo, the scene and both eyes' renderers, the views' codes, the babbles and the
associations' states."""


def run_box(
    config: ICubConfig,
    seeds: Sequence[int],
    *,
    executor: Executor | None = None,
    progress: Progress | None = None,
) -> ICubBoxResult:
    """The 3-D task on ``seeds`` (the module's account)."""
    t0 = time.perf_counter()
    jobs = [(str(s), _BoxJob(config, s, i == 0)) for i, s in enumerate(seeds)]
    values = run_all(
        _box_seed,
        jobs,
        executor=executor,
        per_job=_job_memory(),
        progress=progress,
        desc="icub box",
        describe=lambda key, v: f"seed {key} ({v['seconds']['total']:.0f} s)",
    )
    res = ICubBoxResult(config, tuple(seeds), [values[str(s)] for s in seeds])
    res.seconds = time.perf_counter() - t0
    return res


SUMMARIES = (
    "maps",
    "methods",
    "methods_per_seed",
    "fixation_converged",
    "balls",
    "targets",
    "seconds_per_seed",
    "peak_memory_mb",
)
"""The keys of the JSON form computed from the per-seed records."""

_LATER = ("balls",)

_MAP_SCORES = ("order_r2", "error_cm", "error_ratio_to_kmeans", "fold_score")


def _median(rows: list[dict[str, Any]], key: str) -> float:
    return float(np.median([r[key] for r in rows]))


@dataclass
class ICubBoxResult(Result):
    """Outcome of ``sigmapi icub --space box``: one record per seed (the maps' scores, the
    reaches), pooled (the module's account)."""

    config: ICubConfig
    seeds: tuple[int, ...]
    per_seed: list[dict[str, Any]] = field(default_factory=list)
    seconds: float = 0.0

    KEYS = (
        "experiment",
        "space: config.space",
        "config",
        "seeds",
        *SUMMARIES,
        "seconds",
    )
    """The JSON form: the config and seeds, per map and per method the pooled numbers, per
    seed the methods' numbers, the targets, the time and the peak memory."""
    LATER = _LATER
    """Computed keys that files written before them lack (``balls``: since ``--box-balls``)."""
    COMPUTED = tuple(k for k in SUMMARIES if k not in _LATER)
    experiment = "icub"

    def maps(self) -> dict[str, dict[str, Any]]:
        """Per map: the medians over seeds (``order_r2_per_axis`` per axis), the worst order
        on any axis, how many seeds were ordered and flagged, the references, per seed."""
        out: dict[str, dict[str, Any]] = {}
        for name in ("map_head", "map_torso"):
            rows = [s["maps"][name] for s in self.per_seed]
            axes = np.array([r["order_r2_per_axis"] for r in rows])
            out[name] = {
                **{k: _median(rows, k) for k in _MAP_SCORES},
                "order_r2_per_axis": [float(a) for a in np.median(axes, axis=0)],
                "order_r2_per_axis_worst": float(axes.min()),
                "ordered_seeds": int(sum(bool(r["ordered"]) for r in rows)),
                "folded_seeds": int(sum(bool(r["folded"]) for r in rows)),
                "true_position": {
                    "order_r2": _median([r["true_position"] for r in rows], "order_r2"),
                    "error_cm": _median([r["true_position"] for r in rows], "error_cm"),
                },
                "kmeans": {"error_cm": _median([r["kmeans"] for r in rows], "error_cm")},
                "per_seed": [
                    {
                        "order_r2": r["order_r2"],
                        "order_r2_per_axis": r["order_r2_per_axis"],
                        "folded": r["folded"],
                        "error_cm": r["error_cm"],
                        "error_ratio_to_kmeans": r["error_ratio_to_kmeans"],
                    }
                    for r in rows
                ],
            }
        return out

    def _pooled(self, cond: str, method: str, keep: Any = slice(None)) -> dict[str, Any]:
        """Over every reach of every seed (``keep``: a mask over those reaches)."""

        def every(key: str) -> Any:
            return np.concatenate([s[key][cond][method] for s in self.per_seed])[keep]

        e, aim = 100.0 * every("end_point_m"), 100.0 * every("aim_m")
        strict, touched = every("strict"), every("touched")
        return {
            "end_point_cm": {
                "median": float(np.median(e)),
                "p90": float(np.percentile(e, 90)),
            },
            "aim_cm": {"median": float(np.median(aim)), "p90": float(np.percentile(aim, 90))},
            "strict_success": float(np.mean(strict)),
            "success": float(np.mean(touched)),
        }

    def methods(self) -> dict[str, dict[str, Any]]:
        """Per method, over every reach of every seed with the eyes free: ``end_point_cm``
        (``median``, ``p90``), ``aim_cm`` (the marker at the posture to the ball's centre,
        :attr:`~sigmapi.experiments.icub.reach3d.Reach3D.aim`), ``strict_success``,
        ``success`` (touched); the same after a fixation under ``fixated``."""
        return {
            m: {**self._pooled("free", m), "fixated": self._pooled("fixated", m)} for m in METHODS
        }

    def balls(self) -> dict[str, Any] | None:
        """Where the test balls were put (``config.box_balls``), the share of them the
        scripted IK rests on the palm within
        :data:`~sigmapi.experiments.icub.reach3d.REACHABLE`, and per method (eyes free) the
        pooled numbers of :meth:`methods` over those reachable balls alone; ``None`` for
        records without the IK's errors (written before they were kept)."""
        if any("ik_error_m" not in s for s in self.per_seed):
            return None
        reachable = np.concatenate([s["ik_error_m"] for s in self.per_seed]) < REACHABLE
        return {
            "placed": self.config.box_balls,
            "reachable_share": float(np.mean(reachable)),
            "reachable": {m: self._pooled("free", m, reachable) for m in METHODS},
        }

    def methods_per_seed(self) -> dict[str, dict[str, list[Any]]]:
        """Per method, per seed (eyes free): the end-point error's median and 90th
        percentile (cm) and the strict success, as each seed's record summarises them."""
        out: dict[str, dict[str, list[Any]]] = {}
        for m in METHODS:
            rows = [s["reaches"]["free"][m] for s in self.per_seed]
            out[m] = {
                "end_point_cm_median": [r["end_point_cm"]["median"] for r in rows],
                "end_point_cm_p90": [r["end_point_cm"]["p90"] for r in rows],
                "strict_success": [r["strict_success"] for r in rows],
            }
        return out

    def fixation_converged(self) -> float:
        """The share of the reach tests' balls the fixation converged on (all seeds)."""
        return float(np.mean([s["fixation_converged"] for s in self.per_seed]))

    def _met(self, per: dict[str, dict[str, list[Any]]]) -> dict[str, list[bool]]:
        """Per target of the reaches, per seed: met."""
        lrn, true = per["learned"], per["true_position"]
        ret, rnd = per["retina"], per["random_posture"]
        bound = TARGETS3D
        ep, ept = lrn["end_point_cm_median"], true["end_point_cm_median"]
        return {
            "learned_end_point_cm": [e <= bound["learned_end_point_cm"] for e in ep],
            "learned_end_point_over_true": [
                e <= bound["learned_end_point_over_true"] * t for e, t in zip(ep, ept, strict=True)
            ],
            "learned_strict_success": [
                s >= bound["learned_strict_success"] for s in lrn["strict_success"]
            ],
            "random_posture_strict_success": [
                s <= bound["random_posture_strict_success"] for s in rnd["strict_success"]
            ],
            "learned_minus_retina": [
                a - b >= bound["learned_minus_retina"]
                for a, b in zip(lrn["strict_success"], ret["strict_success"], strict=True)
            ],
        }

    def targets(self) -> dict[str, object]:
        """Each target of :data:`TARGETS3D` (eyes free), pooled over the seeds, and on how many
        seeds it was met."""
        meth, maps = self.methods(), self.maps()
        lrn = meth["learned"]
        ep, ept = lrn["end_point_cm"]["median"], meth["true_position"]["end_point_cm"]["median"]
        bound = TARGETS3D
        n = len(self.seeds)
        return {
            "learned_end_point_cm": ep <= bound["learned_end_point_cm"],
            "learned_end_point_over_true": ep <= bound["learned_end_point_over_true"] * ept,
            "learned_strict_success": lrn["strict_success"] >= bound["learned_strict_success"],
            "random_posture_strict_success": (
                meth["random_posture"]["strict_success"] <= bound["random_posture_strict_success"]
            ),
            "learned_minus_retina": (
                lrn["strict_success"] - meth["retina"]["strict_success"]
                >= bound["learned_minus_retina"]
            ),
            "maps_ordered_all_seeds": all(
                m["ordered_seeds"] == n and m["folded_seeds"] == 0 for m in maps.values()
            ),
            "map_error_ratio_to_kmeans": all(
                m["error_ratio_to_kmeans"] <= bound["map_error_ratio_to_kmeans"]
                for m in maps.values()
            ),
            "seeds_met": {k: int(sum(v)) for k, v in self._met(self.methods_per_seed()).items()},
            "bounds": bound,
        }

    def seconds_per_seed(self) -> list[float]:
        return [float(s["seconds"]["total"]) for s in self.per_seed]

    def peak_memory_mb(self) -> float:
        """The largest peak resident memory of a seed's job, MB."""
        return float(max(s["peak_rss_mb"] for s in self.per_seed))

    def table(self) -> str:
        """Console text: the maps, then the reaches per method (eyes free, then fixated)."""
        maps, meth = self.maps(), self.methods()
        lines = [f"icub --space box: seeds {list(self.seeds)}, {self.seconds:.0f} s"]
        lines.append(
            f"{'map':<10}{'order R2':>9}{'per axis x y z':>18}{'folded':>7}{'err cm':>8}"
            f"{'k-means':>8}{'true map':>9}"
        )
        for name, m in maps.items():
            axes = " ".join(f"{a:.2f}" for a in m["order_r2_per_axis"])
            lines.append(
                f"{name:<10}{m['order_r2']:>9.3f}{axes:>18}{m['folded_seeds']:>7d}"
                f"{m['error_cm']:>8.2f}{m['kmeans']['error_cm']:>8.2f}"
                f"{m['true_position']['error_cm']:>9.2f}"
            )
        balls = self.balls()
        if balls is not None:
            lines.append(
                f"test balls: {balls['placed']}, {balls['reachable_share']:.2f} of them reachable"
                f" (the scripted IK within {100 * REACHABLE:g} cm)"
            )
        lines.append(
            f"{'method':<15}{'end point cm':>13}{'p90':>7}{'strict':>8}{'touch':>7}"
            f"{' | fixated: end point':>21}{'strict':>8}"
        )
        for name, r in meth.items():
            f = r["fixated"]
            lines.append(
                f"{name:<15}{r['end_point_cm']['median']:>13.2f}{r['end_point_cm']['p90']:>7.2f}"
                f"{r['strict_success']:>8.2f}{r['success']:>7.2f}"
                f"{f['end_point_cm']['median']:>21.2f}{f['strict_success']:>8.2f}"
            )
        return "\n".join(lines)

    def figure(self, out_dir: Path) -> list[Path]:
        """The end-point error histogram per method (eyes free;
        :func:`~sigmapi.experiments.icub.plots3d.end_point_histogram`), the first seed's
        filmed reach as a strip and both eyes' frames with the detections
        (:func:`~sigmapi.experiments.icub.plots3d.film_and_eyes`), the maps' middle slices
        (:func:`~sigmapi.experiments.icub.plots3d.map_slices`); with ``config.render``,
        the filmed reach as an animated GIF."""
        from sigmapi._outputs import save_gif
        from sigmapi.experiments.icub.plots3d import end_point_histogram, film_and_eyes, map_slices

        check_records(self.per_seed, "sigmapi icub --space box ... --out DIR")
        errors = {
            m: 100.0 * np.concatenate([s["end_point_m"]["free"][m] for s in self.per_seed])
            for m in METHODS
        }
        paths = [end_point_histogram(errors, Path(out_dir) / "end_point_histogram.png")]
        first = self.per_seed[0]
        paths += film_and_eyes(first, self.seeds[0], Path(out_dir))
        if first.get("units"):
            out = Path(out_dir) / "map-slices.png"
            paths.append(map_slices(first["units"], first["maps"], self.seeds[0], out))
        if self.config.render is not None and first.get("film"):
            paths.append(save_gif(first["film"], Path(self.config.render), fps=8))
        return paths
