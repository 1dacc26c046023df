"""The tables of the neurons results page (``docs/results/neurons.md``), registered with the
``results-table`` directive of :mod:`sigmapi_results` (which imports this module)."""

from __future__ import annotations

from typing import Any

from sigmapi_results import Table, _command, _rel, load, num, result, seeds_label, table


def _neurons_result() -> dict[str, Any]:
    """``benchmarks/results/neurons.json`` read by :class:`NeuronsResult`, as its JSON form."""
    return dict(result("neurons").to_dict())


def _mw(m: dict[str, Any], key: str, fmt: str = ".3f") -> str:
    return f"{num(m[key], fmt)} / {num(m[key + '_worst'], fmt)}"


@table("neurons")
def _neurons() -> Table:
    """The rate maps of ``sigmapi neurons``: medians / worst seeds per map and task."""
    data = _neurons_result()
    acc = {(c["name"], c["task"]): c for c in data["acceptance"]["dendritic"]}
    rows = []
    for m in data["methods"]:
        if m["kind"] != "rate":
            continue
        c = acc.get((m["name"], m["task"]))
        gap = "-" if c is None else (f"{num(c['vc_gap_median'], '+.3f')} / "
                                     f"{num(c['vc_gap_worst'], '+.3f')} ({c['met']} of "
                                     f"{c['n_seeds']})")  # fmt: skip
        rfi = m.get("reference_frame_index")
        rows.append([
            f"`{m['name']}`", m["task"], f"{m['synapses']:,}", _mw(m, "view_consistency"), gap,
            _mw(m, "z_error"), _mw(m, "order_r2"), f"{m['ordered']} of {m['n_seeds']}",
            "-" if rfi is None else num(rfi, ".2f"),
        ])  # fmt: skip
    st = data["settings"]
    two_d = f"2-D: the first {st['seeds_2d']}" if st["preset_2d"] else "no 2-D task"
    note = (f"Seeds {seeds_label(st['seeds'])} ({two_d}); no setting was "
            f"chosen on them (tuning seeds 0-2). Cells: median / worst seed. Gap: view "
            f"consistency minus the Sigma-Pi map's on the same seed (seeds within 0.02 and "
            f"ordered). Synapses per map unit (the basis-function map: its readout plus its "
            f"share of the hidden layer's; sparse dendritic maps: the most in any unit, two "
            f"per branch). RF index: median reference-frame index of the "
            f"units (1-D).")  # fmt: skip
    return Table(["map", "task", "synapses", "view consistency", "gap to Sigma-Pi", "z error",
                  "order R²", "ordered", "RF index"], rows, [_rel("neurons")], note,
                 _command(load("neurons")))  # fmt: skip


@table("neurons-spiking")
def _spiking() -> Table:
    """The spiking networks of ``sigmapi neurons`` per window and peak rate."""
    data = _neurons_result()
    rows = []
    for m in data["methods"]:
        if m["kind"] != "spiking":
            continue
        rows.append([
            f"`{m['name']}`", f"{m['peak_rate']:g} Hz", f"{m['window_ms']:g} ms",
            _mw(m, "agreement"), _mw(m, "view_consistency"),
            f"{num(m['vc_gap'], '+.3f')} / {num(m['vc_gap_worst'], '+.3f')}",
            _mw(m, "z_error"), num(m["spikes_per_decision"], ",.0f"),
        ])  # fmt: skip
    n = next((m["n_trials"] for m in data["methods"] if m["kind"] == "spiking"), 0)
    note = (f"{n} trials per seed (both views of {n // 2} test z's); median / worst seed. Gap: "
            f"view consistency minus the rate map's on the same trials. Spikes per decision: "
            f"input, coincidence and map spikes in the window.")  # fmt: skip
    return Table(["network", "peak rate", "window", "agreement with the rate map",
                  "view consistency", "gap to the rate map", "z error", "spikes per decision"],
                 rows, [_rel("neurons")], note, _command(load("neurons")))  # fmt: skip


@table("neurons-spiking-115-124")
def _spiking_fresh() -> Table:
    """``benchmarks/bench_neurons_spiking.py`` on fresh seeds 115-124, per window."""
    data = load("neurons-spiking-115-124")
    n = len(data["seeds"])
    rows = [
        [f"{s['window_ms']:g} ms", num(s["agreement_median"]), num(s["agreement_worst"]),
         num(s["vc_gap_median"], "+.3f"), num(s["vc_gap_worst"], "+.3f"),
         f"{s['within_002']} of {s['n_seeds']}", num(s["spikes_per_decision"], ",.0f")]
        for s in data["summary"]
    ]  # fmt: skip
    note = (f"The conjunction network at {data['peak_rate']} Hz on seeds "
            f"{seeds_label(data['seeds'])} ({n} seeds, none used to choose anything), "
            f"{2 * data['test_z']} trials per seed (both views of {data['test_z']} test z's); "
            f"pools of {data['pool']}, coincidence window {data['coincidence_ms']:g} ms, gain "
            f"{data['spike_gain']:g}, inhibition {data['spike_inhibition']:g}. Gap: view "
            f"consistency minus the rate map's on the same trials; within: seeds whose gap is "
            f"at least -0.02. Spikes per decision (median over seeds): input, coincidence and "
            f"map spikes in the window.")  # fmt: skip
    return Table(["window", "agreement (median)", "agreement (worst)", "gap (median)",
                  "gap (worst)", "within 0.02", "spikes per decision"], rows,
                 [_rel("neurons-spiking-115-124")], note, _command(data))  # fmt: skip


@table("physiology")
def _physiology() -> Table:
    """``benchmarks/bench_physiology.py``: trained maps against their random starts."""
    return _physiology_of("physiology")


@table("physiology-icub")
def _physiology_icub() -> Table:
    """``benchmarks/bench_physiology.py --icub``: the iCub's two maps, each against the body
    frame it should code (map 1: the head's, map 2: the torso's)."""
    return _physiology_of("physiology-icub")


def _physiology_of(name: str) -> Table:
    data = load(name)
    rows = []
    for r in data["rows"]:
        t, s = r["trained"], r["random_start"]
        rows.append([
            f"`{r['model']}`", "x".join(map(str, r["map_shape"])),
            num(t["median_reference_frame_index"], ".2f"), num(t["measured"], ".2f"),
            num(t["body_centred_share"], ".2f"), num(s["median_reference_frame_index"], ".2f"),
            num(s["measured"], ".2f"), f"{num(r['ks'], '.2f')} (p = {num(r['p_value'], '.1e')})",
            num(t["median_peak_modulation"], ".2f"), num(s["median_peak_modulation"], ".2f"),
        ])  # fmt: skip
    note = ("Reference-frame index: 0 eye-centred, 1 body-centred (median over the units "
            "measured: a strong field that the retina's edge does not cut off, at 3 or more "
            "of the 5 gazes). Body-centred share: units with "
            "index >= 0.8. Peak modulation: (max - min) / (max + min) of a unit's best response "
            "over the gazes.")  # fmt: skip
    return Table(["model", "map", "trained: RF index", "measured", "body-centred share",
                  "random start: RF index", "measured", "KS (p)", "peak modulation, trained",
                  "random"], rows, [_rel(name)], note, _command(data))  # fmt: skip


@table("neurons-sparse")
def _sparse() -> Table:
    """``benchmarks/bench_neurons_sparse.py``: sparse dendritic maps, capacity and learning."""
    data = load("neurons-sparse")
    kinds = {"capacity": "branches set from the Sigma-Pi weights",
             "learned-map": "learned, pruning budget over the map",
             "learned-unit": "learned, D branches in every unit"}  # fmt: skip
    rows = [
        [kinds[s["kind"]], str(s["branches"]), num(s["synapses_mean"], ".0f"),
         str(s["synapses_max"]),
         f"{num(s['vc_gap_median'], '+.3f')} / {num(s['vc_gap_worst'], '+.3f')}",
         f"{s['ordered']} of {s['n_seeds']}", f"{s['met']} of {s['n_seeds']}"]
        for s in data["summary"]
    ]  # fmt: skip
    note = (f"Seeds {seeds_label(data['seeds'])}, {data['preset']}; settings chosen on seeds "
            f"0-2. Two synapses per branch; synapses per unit: mean over units and the most in "
            f"any unit (a Sigma-Pi unit has 225 weights). Gap: view consistency minus the "
            f"Sigma-Pi map's on the same seed, median / worst. Met: within 0.02 and "
            f"ordered.")  # fmt: skip
    return Table(["map", "branches D", "synapses (mean)", "synapses (most)",
                  "gap to Sigma-Pi", "ordered", "met"], rows, [_rel("neurons-sparse")], note,
                 _command(data))  # fmt: skip
