"""Figures of ``sigmapi neurons`` and ``sigmapi physiology``, drawn from their result dicts.

Every mark has a legend entry (or a colour bar, where colour carries a value); the legends sit
below their panels, off the data."""

from __future__ import annotations

from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from sigmapi.viz.series import legend_once

__all__ = ["neurons_figure", "physiology_figure"]

_BELOW = {"loc": "upper center", "bbox_to_anchor": (0.5, -0.16), "borderaxespad": 0.0}
"""Legend keywords: below the panel, under its x label."""


def neurons_figure(result: dict[str, Any]) -> Figure:
    """Three panels: view consistency against synapses per unit (1-D maps), the spiking
    networks against the decision window at the reference rate, the branches of one map."""
    fig, axes = plt.subplots(1, 3, figsize=(15, 6.2), layout="constrained")
    ax = axes[0]
    rate = [m for m in result["methods"] if m["kind"] == "rate" and m["task"] == "1d"]
    sp = next(m for m in rate if m["name"] == "sigma-pi")
    ax.axhspan(
        sp["view_consistency"] - 0.02,
        sp["view_consistency"],
        color="0.85",
        label="within 0.02 of Sigma-Pi",
    )
    groups = (
        ("dendritic-D", "dense dendritic (median, worst)", "o"),
        ("dendritic-sparse-D", "sparse dendritic, 2 synapses per branch", "D"),
    )
    for prefix, label, marker in groups:
        dend = [m for m in rate if m["name"].startswith(prefix)]
        if not dend:
            continue
        ax.errorbar(
            [m["synapses"] for m in dend],
            [m["view_consistency"] for m in dend],
            yerr=[
                [m["view_consistency"] - m["view_consistency_worst"] for m in dend],
                [0.0] * len(dend),
            ],
            marker=marker,
            capsize=3,
            label=label,
        )
        for m in dend:
            ax.annotate(
                f"D={m['branches']}",
                (m["synapses"], m["view_consistency"]),
                textcoords="offset points",
                xytext=(4, -12),
                fontsize=8,
            )
    for m, mk in ((sp, "s"), (next(m for m in rate if m["name"] == "basis-function"), "^")):
        ax.errorbar(
            [m["synapses"]],
            [m["view_consistency"]],
            yerr=[[m["view_consistency"] - m["view_consistency_worst"]], [0.0]],
            marker=mk,
            capsize=3,
            linestyle="none",
            label=m["name"],
        )
    ax.set_xlabel("synapses per map unit (the most in any unit)")
    ax.set_ylabel("view consistency (same winner)")
    ax.set_title("1-D maps of first-order neurons")
    ax.legend(fontsize=8, **_BELOW)

    ax = axes[1]
    spk = [m for m in result["methods"] if m["kind"] == "spiking" and m["peak_rate"] == 100]
    for base, colour in (
        ("spiking-conjunction", "C0"),
        ("spiking-dendritic", "C1"),
        ("spiking-sparse-dendritic", "C2"),
    ):
        rows = sorted(
            (m for m in spk if m["name"].startswith(base + "-") and "-pool" not in m["name"]),
            key=lambda m: m["window_ms"],
        )
        if not rows:
            continue
        w = [m["window_ms"] for m in rows]
        ax.plot(
            w,
            [m["vc_gap"] for m in rows],
            "o-",
            color=colour,
            label=f"{base}: view consistency - rate map's",
        )
        ax.plot(
            w,
            [m["agreement"] - 1.0 for m in rows],
            "s--",
            color=colour,
            label=f"{base}: agreement - 1",
        )
    ax.axhline(-0.02, color="0.5", lw=0.8, ls=":", label="-0.02: the acceptance margin")
    ax.set_xscale("log")
    ticks = sorted({m["window_ms"] for m in spk})
    ax.set_xticks(ticks, [f"{t:g}" for t in ticks])
    ax.minorticks_off()
    ax.set_xlabel("decision window (ms)")
    ax.set_ylabel("difference (median over seeds)")
    ax.set_title("spiking networks, 100 Hz peak rate")
    ax.legend(fontsize=7, **_BELOW)

    ax = axes[2]
    b = result["branches"][0]
    unit = np.asarray(b["unit"])
    xc, yc = np.asarray(b["x_centre"])[:, 0], np.asarray(b["y_centre"])[:, 0]
    dots = ax.scatter(xc, yc, c=unit, cmap="viridis", s=18, label="a branch")
    fig.colorbar(dots, ax=ax, label="map unit of the branch")
    n = float(max(xc.max(), yc.max())) + 1.0
    for i, s in enumerate(np.arange(0, 2 * n, 2.0)):
        label = "retinal + gaze centre constant (one z)" if i == 0 else "_z"
        ax.plot([0, s], [s, 0], color="0.75", lw=0.6, zorder=0, label=label)
    ax.set_xlim(-0.5, n)
    ax.set_ylim(-0.5, n)
    ax.set_xlabel("retinal centre of a branch's synapses (grid units, axis 0)")
    ax.set_ylabel("gaze centre (grid units, axis 0)")
    ax.set_title(f"branches of the D={b['branches']} map (colour: unit)")
    ax.legend(fontsize=8, **_BELOW)
    return fig


def physiology_figure(result: dict[str, Any]) -> Figure:
    """Reference-frame index distributions (trained map against its random start), tuning
    curves of three units at every gaze, and the gain-field fits; below, the monkey protocol
    beside the published numbers (where the result has one)."""
    monkey = result.get("monkey")
    rows = 2 if monkey else 1
    fig, grid = plt.subplots(rows, 3, figsize=(16, 5.6 * rows), squeeze=False, layout="constrained")
    axes = grid[0]
    if monkey:
        _monkey_panels(grid[1], monkey)
    ax = axes[0]
    bins = np.linspace(-1.5, 2.0, 36)
    for key, label in (("trained", "trained map"), ("random_start", "random start")):
        vals = [v for v in result[key]["reference_frame_index"] if v is not None]
        med = result[key]["median_reference_frame_index"]
        text = "no unit measured" if med is None else f"median {med:.2f}, n={len(vals)}"
        ax.hist(np.clip(vals, bins[0], bins[-1]), bins=bins, alpha=0.6, label=f"{label} ({text})")
    ax.axvline(0.0, color="0.4", ls=":", label="0: eye-centred, 1: body-centred")
    ax.axvline(1.0, color="0.4", ls=":", label="_body")
    ax.set_xlabel("reference-frame index (0 eye-centred, 1 body-centred)")
    ax.set_ylabel("units")
    ax.legend(fontsize=8, **_BELOW)

    ax = axes[1]
    curves = result["tuning"]
    probes = np.asarray(curves["positions"])
    for c, unit in enumerate(curves["units"]):
        for g, resp in zip(curves["gazes"], curves["responses"][c], strict=True):
            ax.plot(probes, resp, color=f"C{c}", alpha=0.35 + 0.65 * g)
        ax.plot([], [], color=f"C{c}", label=f"unit {unit}")
    ax.set_xlabel("retinal position (fraction of the axis)")
    ax.set_ylabel("response")
    ax.set_title(
        "tuning curves at gazes "
        + ", ".join(f"{g:g}" for g in curves["gazes"])
        + " (darker: larger)"
    )
    ax.legend(fontsize=8, **_BELOW)

    ax = axes[2]
    for key, label in (("trained", "trained map"), ("random_start", "random start")):
        mod = [v for v in result[key]["peak_modulation"] if v is not None]
        pairs = [
            (a, b)
            for a, b in zip(result[key]["gain_r2"], result[key]["gain_slope"], strict=True)
            if a is not None and b is not None
        ]
        text = f"{np.median(mod):.2f}" if mod else "-"
        ax.scatter(
            [a for a, _ in pairs],
            [b for _, b in pairs],
            s=10,
            alpha=0.6,
            label=f"{label}: peak modulation median {text}",
        )
    ax.set_xlabel("planar gain-field fit R^2 (response at fixed retinal position)")
    ax.set_ylabel("gain slope (|b| / mean response)")
    ax.legend(fontsize=8, **_BELOW)
    return fig


def _monkey_panels(axes: Any, m: dict[str, Any]) -> None:
    """The gain-field studies' protocol on the map beside the monkeys' numbers: the share of
    gain-modulated units, the reference-frame index of the admitted and left-out units, and
    the planarity of the admitted units' gain fields."""
    ax = axes[0]
    bars: list[tuple[str, float, bool, str]] = []
    if m["gain_modulated_share"] is not None:
        bars.append((f"map, admitted (n={m['admitted']})", m["gain_modulated_share"], True, "C0"))
    bars.append((f"map, every unit (n={m['units']})", m["gain_modulated_share_all"], True, "C0"))
    for p in m["published"]:
        if p["measure"] != "gain_modulated_share":
            continue
        values = p["value"] if isinstance(p["value"], list) else [p["value"]]
        author = p["study"].split(",")[0].split(" ")[0]
        year = p["study"].split(",")[-2].strip().split(" ")[-1]
        for i, v in enumerate(values):
            area = p["area"].split(" / ")[i] if len(values) > 1 else p["area"]
            label = f"{author} {year} {area}" + (" (> half)" if p.get("bound") else "")
            bars.append((label, float(v), bool(p["verified"]), "C1"))
    ys = np.arange(len(bars))
    for y, (_, v, ok, colour) in zip(ys, bars, strict=True):
        who = "the map" if colour == "C0" else "published"
        ax.barh(
            y,
            v,
            color=colour,
            alpha=0.75 if ok else 0.35,
            hatch=None if ok else "//",
            label=who if ok else f"{who}, not verified against the paper",
        )
        ax.text(min(v, 0.98), y, f" {100 * v:.0f} %", va="center", ha="right", fontsize=7)
    ax.set_yticks(ys, [b[0] for b in bars], fontsize=7)
    ax.invert_yaxis()
    ax.set_xlim(0, 1)
    ax.set_xlabel("share of units with an eye-position effect")
    ax.set_title(
        f"eye-position effect: ANOVA over the fixations, p < {m['alpha']:g}\n"
        "(hatched: not verified against the paper)",
        fontsize=8,
    )
    legend_once(ax, fontsize=7, **_BELOW)

    ax = axes[1]
    per = m["per_unit"]
    adm = [v for v in per["reference_frame_index"] if v is not None]
    out = [
        v
        for v, a in zip(per["reference_frame_index_all"], per["admitted"], strict=True)
        if v is not None and not a
    ]
    bins = np.linspace(-0.5, 1.5, 41)
    ax.hist(np.clip(out, bins[0], bins[-1]), bins=bins, alpha=0.5, color="0.5",
            label=f"left out, every fixation (n={len(out)})")  # fmt: skip
    ax.hist(np.clip(adm, bins[0], bins[-1]), bins=bins, alpha=0.8, color="C0",
            label=f"admitted (n={len(adm)})")  # fmt: skip
    shifted = [v for v in per["displacement_index"] if v is not None]
    ax.hist(np.clip(shifted, bins[0], bins[-1]), bins=bins, histtype="step", color="C3", lw=1.5,
            label=f"admitted, by cross-correlation (n={len(shifted)})")  # fmt: skip
    ax.axvline(0.0, color="0.4", ls=":", label="0: eye-centred, 1: body-centred")
    ax.axvline(1.0, color="0.4", ls=":", label="_body")
    ax.axvspan(0.0, 1.0, color="C1", alpha=0.08,
               label="VIP: from eye- to head-centred\n(Duhamel 1997, Avillac 2005)")  # fmt: skip
    ax.set_xlabel("reference-frame index, monkey grid\n(0 eye-centred, 1 body-centred)")
    ax.set_ylabel("units")
    ax.legend(fontsize=7, **_BELOW)

    ax = axes[2]
    r2 = [v for v, a in zip(per["gain_r2"], per["admitted"], strict=True) if a and v is not None]
    text = f"admitted units (median {np.median(r2):.2f})" if r2 else "no unit admitted"
    ax.hist(r2, bins=np.linspace(0, 1, 21), color="C0", alpha=0.8, label=text)
    ax.set_xlabel("planar gain-field fit R^2\n(rate at the best stimulus over the fixations)")
    ax.set_ylabel("units")
    ax.set_title("7a/LIP: 'usually planar or largely planar' (Andersen 1990)", fontsize=8)
    ax.legend(fontsize=7, **_BELOW)
