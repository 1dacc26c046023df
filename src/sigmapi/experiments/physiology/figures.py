"""The figure of ``sigmapi physiology``, drawn from its result dict.

Every mark has a legend entry (or a colour bar, where colour carries a value); the legends sit
below their panels, off the data."""

from __future__ import annotations

from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from sigmapi.experiments.kit.figures import BELOW, legend_once


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
    ax.legend(fontsize=8, **BELOW)

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
    ax.legend(fontsize=8, **BELOW)

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
    ax.legend(fontsize=8, **BELOW)
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
    legend_once(ax, fontsize=7, **BELOW)

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
    ax.legend(fontsize=7, **BELOW)

    ax = axes[2]
    r2 = [v for v, a in zip(per["gain_r2"], per["admitted"], strict=True) if a and v is not None]
    text = f"admitted units (median {np.median(r2):.2f})" if r2 else "no unit admitted"
    ax.hist(r2, bins=np.linspace(0, 1, 21), color="C0", alpha=0.8, label=text)
    ax.set_xlabel("planar gain-field fit R^2\n(rate at the best stimulus over the fixations)")
    ax.set_ylabel("units")
    ax.set_title("7a/LIP: 'usually planar or largely planar' (Andersen 1990)", fontsize=8)
    ax.legend(fontsize=7, **BELOW)
