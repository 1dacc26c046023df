"""The result of ``sigmapi neurons``: medians over seeds, the acceptance checks, the figure."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from sigmapi.experiments.kit.results import (
    JSON,
    VC_MARGIN,
    Column,
    Result,
    as_object,
    columns,
    margin_case,
    margin_line,
    render,
    tuples,
    within_margin,
)

from .config import METRICS, PHYSIOLOGY, REFERENCE_RATE, NeuronsConfig

Row = JSON
"""A record of the JSON form: a map's or a spiking network's row of one job (its name, task,
seed and scores), an entry of :meth:`NeuronsResult.methods`, a branch summary."""


MAX_WINDOW_MS = 200
"""Acceptance: the spiking network's windows up to this one count."""

_WORST_HIGH = ("z_error", "fold_score", "mean_synapses", "branch_z_gap")

SPARSE = "dendritic-sparse"
"""Name prefix of the sparse dendritic maps."""

RATE_COLUMNS = columns(
    "name:28s task:4s synapses:8d view_consistency:9.3f view_consistency_worst:6.3f",
    "z_error:7.3f order_r2:6.3f",
    Column("ordered", lambda m: f"{m['ordered']:3d}/{m['n_seeds']:<3d}", ">7s"),
    Column("RF index", lambda m: m.get("reference_frame_index"), "8.2f"),
    order_r2="order",
)
"""The table's columns of the rate maps: one row per map and task (medians, worst seed)."""

SPIKING_COLUMNS = columns(
    Column("spiking (peak rate)", lambda m: f"{m['name']} ({m['peak_rate']} Hz)", "28s"),
    "agreement:6.3f view_consistency:9.3f rate_view_consistency:8.3f z_error:7.3f",
    "spikes_per_decision:7.0f",
    agreement="agree",
    rate_view_consistency="rate map",
    spikes_per_decision="spikes",
)
"""The table's columns of the spiking networks: one row per network and peak rate."""


RATE_EXTRA = (*PHYSIOLOGY, "active_synapses", "mean_synapses", "branch_z_gap")
"""What a rate map's entry summarises besides the :data:`METRICS` (where its rows have it)."""
RATE_PER_SEED = ("seed", *METRICS, "folded", "seconds")
SPIKING_PER_SEED = ("seed", "agreement", "view_consistency", "rate_view_consistency")
SPIKING_METRICS = (*SPIKING_PER_SEED[1:], *METRICS[1:4], "spikes_per_decision", "map_spikes")
"""What a spiking network's entry summarises: its per-seed scores, the rate maps' scores of
winners (view within one, z error, order) and its spikes."""


def _groups(rows: list[Row], *keys: str) -> dict[tuple[object, ...], list[Row]]:
    """``rows`` by their values of ``keys``, in the order they first appear."""
    out: dict[tuple[object, ...], list[Row]] = {}
    for r in rows:
        out.setdefault(tuple(r[k] for k in keys), []).append(r)
    return out


def _median_worst(rows: list[Row], keys: tuple[str, ...]) -> Row:
    out: dict[str, object] = {}
    for k in keys:
        vals = [r[k] for r in rows if r.get(k) is not None]
        if not vals:
            out[k] = out[f"{k}_worst"] = None
            continue
        worst = max(vals) if k in _WORST_HIGH else min(vals)
        out.update({k: float(np.median(vals)), f"{k}_worst": float(worst)})
    return out


@dataclass
class NeuronsResult(Result):
    """Every job's rows (:meth:`~sigmapi.experiments.neurons.run.NeuronsExperiment.seed_run`)."""

    config: NeuronsConfig
    seeds: tuple[int, ...]
    runs: dict[str, list[Row]]
    """Every map's (``"maps"``) and spiking network's (``"spiking"``) row per seed and task."""
    branches: list[Row]
    """What the branches of one dendritic map per seed and task learned: branch by branch for
    the first, the summary for the others."""
    seconds: float

    KEYS = ("methods", "acceptance", "branches", "settings: config_and_seeds", "runs", "seconds")
    """The JSON form: :meth:`methods`, :meth:`acceptance`, the branches, the settings (the
    config's fields and the seeds), every row and the time."""
    FIGURE = "neurons.png"
    DRAWN_BY = "sigmapi.experiments.neurons.figures:neurons_figure"
    SAVE: ClassVar[Mapping[str, object]] = {"dpi": 110}

    @classmethod
    def read_fields(cls, obj: Mapping[str, object]) -> Row:
        """The fields of a JSON form (:meth:`Result.read_fields`), the config and the seeds
        from its settings."""
        settings = dict(as_object(obj["settings"], "settings"))
        seeds = tuple(settings.pop("seeds"))
        config = NeuronsConfig(**tuples(settings))
        return {**super().read_fields(obj), "config": config, "seeds": seeds}

    def methods(self) -> list[Row]:
        """One entry per map (and task) and per spiking network, window and peak rate:
        ``name``, ``task``, medians and worst seeds of the metrics, ``ordered``, ``n_seeds``,
        ``synapses`` and ``per_seed``."""
        out = []
        maps = _groups(self.runs["maps"], "task", "name")
        for (task, name), rows in sorted(maps.items(), key=lambda kv: str(kv[0][0])):
            out.append(
                {
                    "name": name,
                    "task": task,
                    "kind": "rate",
                    **_median_worst(rows, METRICS + RATE_EXTRA),
                    "synapses": max(r["synapses"] for r in rows),
                    "branches": rows[0].get("branches"),
                    "ordered": int(sum(not r["folded"] for r in rows)),
                    "n_seeds": len(rows),
                    "per_seed": {k: [r.get(k) for r in rows] for k in RATE_PER_SEED},
                }
            )
        for (name, rate), rows in _groups(self.runs["spiking"], "name", "peak_rate").items():
            gap = [r["view_consistency"] - r["rate_view_consistency"] for r in rows]
            out.append(
                {
                    "name": name if rate == REFERENCE_RATE else f"{name}-{rate}hz",
                    "task": "1d",
                    "kind": "spiking",
                    "window_ms": rows[0]["window_ms"],
                    "peak_rate": rate,
                    "pool": rows[0].get("pool"),
                    **_median_worst(rows, SPIKING_METRICS),
                    "vc_gap": float(np.median(gap)),
                    "vc_gap_worst": float(min(gap)),
                    "n_seeds": len(rows),
                    "n_trials": rows[0]["n_trials"],
                    "per_seed": {k: [r[k] for r in rows] for k in SPIKING_PER_SEED},
                }
            )
        return out

    def acceptance(self) -> Row:
        """Dendritic: per branch count, seed by seed the view consistency minus the Sigma-Pi
        map's, seeds within :data:`VC_MARGIN` and ordered, and whether it has fewer synapses
        than ``n_x n_y``; ``smallest_branches``: the fewest branches every seed meets it with.
        Spiking: per window up to :data:`MAX_WINDOW_MS` at :data:`REFERENCE_RATE`, the gap to
        the rate map's view consistency and the agreement."""
        maps = _groups(self.runs["maps"], "task", "name")
        dendritic = []
        for (task, name), rows in sorted(maps.items(), key=lambda kv: str(kv[0][0])):
            if name == "sigma-pi":
                continue
            ref = {r["seed"]: r for r in maps[task, "sigma-pi"]}
            gap = [r["view_consistency"] - ref[r["seed"]]["view_consistency"] for r in rows]
            most, theirs = max(r["synapses"] for r in rows), ref[rows[0]["seed"]]["synapses"]
            dendritic.append(
                {
                    "name": name,
                    "task": task,
                    "branches": rows[0].get("branches"),
                    "synapses": most,
                    "sigma_pi_synapses": theirs,
                    "fewer_synapses": most < theirs,
                    **margin_case(gap, [r["folded"] for r in rows]),
                }
            )
        out: Row = {"margin": VC_MARGIN, "dendritic": dendritic, "spiking": []}
        for task in ("1d", "2d"):
            ok = [c for c in dendritic if c["task"] == task and c["branches"] and c["all_met"]]
            cheap = [c for c in ok if c["fewer_synapses"]]
            sparse = [c for c in cheap if c["name"].startswith(SPARSE)]
            named = {"branches": ok, "branches_fewer_synapses": cheap, "sparse_branches": sparse}
            for key, these in named.items():
                out[f"smallest_{key}_{task}"] = min((c["branches"] for c in these), default=None)
        spiking = [m for m in self.methods() if m["kind"] == "spiking"]
        for m in spiking:
            own_pool = m["pool"] in (None, self.config.pool)
            if m["peak_rate"] == REFERENCE_RATE and own_pool and m["window_ms"] <= MAX_WINDOW_MS:
                out["spiking"].append(
                    {
                        "name": m["name"],
                        "window_ms": m["window_ms"],
                        "vc_gap_median": m["vc_gap"],
                        "vc_gap_worst": m["vc_gap_worst"],
                        "agreement_median": m["agreement"],
                        "agreement_worst": m["agreement_worst"],
                        "met": within_margin(m["vc_gap_worst"]),
                    }
                )
        return out

    def table(self) -> str:
        """Medians per map, then the spiking networks at the reference rate, then acceptance."""
        methods = self.methods()
        rows = render(RATE_COLUMNS, [m for m in methods if m["kind"] == "rate"])
        rows += render(SPIKING_COLUMNS, [m for m in methods if m["kind"] == "spiking"])
        rows += [
            f"{c['name']} ({c['task']}): {margin_line(c, 'of sigma-pi')}; {c['synapses']} "
            f"synapses per unit against {c['sigma_pi_synapses']}"
            for c in self.acceptance()["dendritic"]
        ]
        return "\n".join(rows)

    def caption(self) -> str:
        """The figure's caption, computed from the result."""
        acc = self.acceptance()
        sp = next(m for m in self.methods() if m["name"] == "sigma-pi" and m["task"] == "1d")
        one_d = [c for c in acc["dendritic"] if c["task"] == "1d" and c["branches"]]
        sparse = [c for c in one_d if c["name"].startswith(SPARSE)]
        best = max((c for c in one_d if c not in sparse), key=lambda c: c["vc_gap_median"])
        n = len(self.seeds)
        text = (
            f"{self.config.preset}, seeds {', '.join(map(str, self.seeds))}. Left: view "
            f"consistency of dendritic maps against synapses per unit (median, worst seed); "
            f"Sigma-Pi map {sp['view_consistency']:.3f} ({sp['synapses']} weights per unit). "
            f"Dense branches (every branch synapses with every input), closest: {best['name']} "
            f"(median gap {best['vc_gap_median']:+.3f}, {best['met']} of {n} seeds within "
            f"{VC_MARGIN} and ordered, {best['synapses']} synapses). "
        )
        small = acc.get("smallest_sparse_branches_1d")
        if sparse and small is None:
            text += (
                f"No sparse map (two clustered synapses per branch) comes within {VC_MARGIN} "
                f"ordered on every seed with fewer synapses than the Sigma-Pi unit. "
            )
        elif sparse:
            c = next(c for c in sparse if c["branches"] == small)
            text += (
                f"Sparse branches (two clustered synapses each, an AND of one retinal and one "
                f"gaze input): {small} branches per unit on average come within {VC_MARGIN} "
                f"and ordered on {c['met']} of {n} seeds (median gap {c['vc_gap_median']:+.3f}, "
                f"worst {c['vc_gap_worst']:+.3f}) with at most {c['synapses']} synapses in any "
                f"unit. "
            )
        spk = acc["spiking"]
        if spk:
            met = [s for s in spk if s["met"]]
            text += (
                f"Middle: spiking networks at {REFERENCE_RATE} Hz against the decision window "
                f"(view consistency minus the rate map's, and agreement with its winners). "
                + (
                    f"Shortest window within {VC_MARGIN} of the rate map on every seed: "
                    f"{min(s['window_ms'] for s in met):g} ms "
                    f"({min(met, key=lambda s: s['window_ms'])['name']}). "
                    if met
                    else f"No window up to {MAX_WINDOW_MS} ms within {VC_MARGIN} on every seed. "
                )
            )
        b = self.branches[0]
        text += (
            f"Right: the branches of the D={b['branches']} map, seed {b['seed']}, as retinal "
            f"against gaze centre, one colour per unit; {100 * b['conjunction_share']:.0f} % "
            f"hold >= 80 % of their retinal and of their gaze weight in one region (a "
            f"conjunction), median distance of a branch's conjunction from its unit's z "
            f"{b['z_gap_median']:.2f} grid units."
        )
        return text
