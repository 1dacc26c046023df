"""The result of ``sigmapi physiology``: the per-unit indices, their distributions, the figure."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from sigmapi._outputs import save_captioned
from sigmapi.experiments.kit.results import Result, columns, render

from .config import PhysiologyConfig

__all__ = ["BODY_CENTRED", "FIGURE", "PhysiologyResult"]

FIGURE = "physiology.png"

BODY_CENTRED = 0.9
"""A map whose median reference-frame index is at least this reads as body-centred."""

COLUMNS = columns(
    "map:14s median_reference_frame_index:9.3f measured:8.2f body_centred_share:12.2f",
    "median_gain_r2:8.3f median_peak_modulation:9.3f",
    body_centred_share="body-centred",
    median_gain_r2="gain R^2",
    median_peak_modulation="peak mod.",
)
"""The table's columns: one row per map (the trained one, its random start)."""


@dataclass
class PhysiologyResult(Result):
    """The recording of one model file (:func:`.run.record_model`)."""

    config: PhysiologyConfig
    data: dict[str, Any]
    seconds: float

    KEYS = ("*data", "body_centred", "settings", "seconds")
    """The JSON form: ``reference_frame_index`` (per unit, the trained map), ``trained`` and
    ``random_start`` (every index per unit, medians), ``comparison`` (Kolmogorov-Smirnov
    between the two index distributions), ``tuning``, ``monkey`` (the gain-field studies'
    protocol, :func:`~sigmapi.analysis.monkey.monkey_protocol`, with the published numbers),
    the verdict (:meth:`body_centred`), the settings and the time."""

    def body_centred(self) -> bool:
        """Whether the trained map's median reference-frame index is at least
        :data:`BODY_CENTRED`."""
        med = self.data["trained"]["median_reference_frame_index"]
        return med is not None and med >= BODY_CENTRED

    def settings(self) -> dict[str, Any]:
        """The config's fields but the tuning units."""
        c = self.config
        return {
            "model": c.model,
            "gazes": c.gazes,
            "n_probe": c.n_probe,
            "body_slope": c.body_slope,
            "gaze_axes": c.gaze_axes,
            "eye_grid": c.eye_grid,
            "n_retina": c.n_retina,
            "responds": c.responds,
            "nwb": c.nwb,
        }

    def table(self) -> str:
        """The medians of both maps and the comparison."""
        rows = render(COLUMNS, [{"map": k, **self.data[k]} for k in ("trained", "random_start")])
        c = self.data["comparison"]
        if c["ks"] is not None:
            rows.append(
                f"trained vs random start: KS {c['ks']:.3f}, p = {c['p_value']:.2g} "
                f"(n = {c['n'][0]}, {c['n'][1]})"
            )
        rows.append(self._monkey_line())
        return "\n".join(rows)

    def _monkey_line(self) -> str:
        m = self.data["monkey"]
        share = m["gain_modulated_share"]
        idx, r2 = m["reference_frame_index"]["median"], m["gain_r2"]["median"]
        left = ", ".join(f"{v} {k.replace('_', ' ')}" for k, v in m["left_out"].items())
        return (
            f"monkey protocol ({len(m['fixations'])} fixations, {m['n_retina']} stimuli per "
            f"axis): {m['admitted']} of {m['units']} units admitted (left out: {left}); "
            + (f"gain-modulated {100 * share:.0f} %" if share is not None else "no unit admitted")
            + (f", planar-fit R^2 median {r2:.2f}" if r2 is not None else "")
            + (f", reference-frame index median {idx:.2f}" if idx is not None else "")
            + (
                f" (by cross-correlation {m['displacement_index']['median']:.2f})"
                if m["displacement_index"]["median"] is not None
                else ""
            )
            + (
                f" (every unit: {m['reference_frame_index_all']['median']:.2f})"
                if m["reference_frame_index_all"]["median"] is not None
                else ""
            )
        )

    def caption(self) -> str:
        """The figure's caption, computed from the data."""
        t, s, c = self.data["trained"], self.data["random_start"], self.data["comparison"]

        def med(r: dict[str, Any]) -> str:
            v = r["median_reference_frame_index"]
            return "no unit measured" if v is None else f"median {v:.2f}"

        verdict = (
            "body-centred"
            if self.body_centred()
            else f"not body-centred by the {BODY_CENTRED} criterion"
        )
        text = (
            f"{self.data['model']} (map {'x'.join(map(str, self.data['map_shape']))}): "
            f"reference-frame index (receptive-field shift with gaze over a body-centred "
            f"field's; 0 eye-centred, 1 body-centred) of the trained map, {med(t)} over "
            f"{100 * t['measured']:.0f} % of units with a field at >= 3 gazes: {verdict}; "
            f"its random start, {med(s)}."
        )
        if c["ks"] is not None:
            text += f" The two distributions differ by KS {c['ks']:.2f} (p = {c['p_value']:.2g})."
        text += (
            f" Middle: tuning curves over retinal position at gazes "
            f"{', '.join(f'{g:g}' for g in self.config.gazes)}. Right: planar gain-field fits "
            f"of the response at a fixed retinal position (median R^2 trained "
            f"{t['median_gain_r2']:.2f}, random {s['median_gain_r2']:.2f}); the best response's "
            f"modulation over gazes, median trained {t['median_peak_modulation']:.2f}, random "
            f"{s['median_peak_modulation']:.2f}."
        )
        text += (
            " Bottom: the gain-field studies' protocol (a grid of fixations, stimuli on a "
            "grid of retinal positions) beside the monkeys' published numbers (hatched: not "
            "verified against the paper): " + self._monkey_line() + "."
        )
        return text

    def figure(self, out_dir: Path) -> list[Path]:
        """``physiology.png`` and its caption ``physiology.txt`` (and the NWB file the run
        wrote there, ``--nwb``, in the list of files written)."""
        from .figures import physiology_figure  # matplotlib: only when drawing

        out = Path(out_dir) / FIGURE
        fig = save_captioned(physiology_figure(self.to_dict()), out, self.caption(), dpi=110)
        nwb = self.data.get("nwb")
        return [fig, *([Path(out_dir) / nwb] if nwb else [])]
