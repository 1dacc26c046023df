"""``sigmapi physiology`` in one module, read top to bottom: its settings
(:class:`PhysiologyConfig`), its result (:class:`PhysiologyResult`: the JSON form, table and
figure), the run, which records the model file's map and its random start
(:func:`record_model`, :class:`PhysiologyExperiment`), and the figure
(:func:`physiology_figure`, matplotlib imported when drawing)."""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi import _validate
from sigmapi._outputs import INPUT, save_captioned
from sigmapi.analysis.monkey import EYE_GRID, N_RETINA, RESPONDS, fixation_protocol, monkey_protocol
from sigmapi.analysis.physiology import (
    GAZES,
    Recordable,
    check_gaze_axes,
    compare_distributions,
    record,
    tuning_curves,
)
from sigmapi.errors import DataError, UsageError
from sigmapi.experiments.base import Experiment, Run, register
from sigmapi.experiments.kit.figures import BELOW, legend_once
from sigmapi.experiments.kit.results import Result, as_object, columns, render, tuples
from sigmapi.model.som import SigmaPiSOM, load_model

if TYPE_CHECKING:
    from matplotlib.figure import Figure

# -- the settings ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class PhysiologyConfig:
    """What ``sigmapi physiology`` records."""

    model: str = field(metadata=INPUT)
    """The model file to record from (``sigmapi train --out FILE``)."""
    gazes: tuple[float, ...] = field(
        default=GAZES,
        metadata=_validate.bounded("numbers", 0, 1, fix="fractions of the gaze axis", sep=","),
    )
    """Gaze directions (fractions of the gaze axis) the units are recorded at."""
    n_probe: int = field(
        default=0, metadata=_validate.bounded("int", 0, 1001, fix="0 for the default, e.g. 61")
    )
    """Probe positions along the swept retinal axis (0: 61; 15 along any other)."""
    tuning_units: int = field(default=3, metadata=_validate.bounded("int", 1, 10, fix="e.g. 3"))
    """Units whose tuning curves the figure shows."""
    body_slope: tuple[float, ...] = field(
        default=(),
        metadata=_validate.bounded("numbers", -100, 100, count=3, fix="e.g. -1", sep=","),
    )
    """How far a body-centred receptive field moves on the retina per unit of gaze, one value
    or one per gaze axis (empty: from the model's relation, -1 for z = (x + y) / 2). A map
    learned from a world of its own geometry needs that world's: the robot's and the iCub's
    are measured by ``benchmarks/bench_physiology.py --robot`` and ``--icub``."""
    gaze_axes: tuple[int, ...] = field(
        default=(),
        metadata=_validate.bounded("ints", 0, 2, count=3, fix="e.g. --gaze-axes 1,0", sep=","),
    )
    """For each retinal axis, the gaze axis that moves the receptive fields along it (empty:
    the same axis). The iCub's retina is (horizontal, vertical) and its gaze codes (tilt,
    pan): ``1,0``."""

    eye_grid: tuple[float, ...] = field(
        default=EYE_GRID,
        metadata=_validate.bounded(
            "numbers", 0, 1, count=21, fix="fractions of the gaze axis", sep=","
        ),
    )
    """The monkey protocol's eye positions along each gaze axis (every combination is a
    fixation; ``0.3,0.5,0.7``: the studies' 3 x 3 grid)."""
    n_retina: int = field(
        default=N_RETINA, metadata=_validate.bounded("int", 5, 101, fix=f"e.g. {N_RETINA}")
    )
    """The monkey protocol's stimulus positions along each retinal axis."""
    responds: float = field(
        default=RESPONDS, metadata=_validate.bounded("number", 0, 1, fix=f"e.g. {RESPONDS}")
    )
    """The monkey protocol counts a field at a fixation where the unit's best response there
    is at least this share of its best at any fixation."""
    nwb: bool = False
    """Also write the recording as an NWB file, physiology.nwb, into --out (needs the nwb
    extra: pip install 'sigmapi[nwb]')."""

    def __post_init__(self) -> None:
        if not isinstance(self.model, str) or not self.model:
            fix = "e.g. sigmapi physiology model.npz"
            raise _validate.fail("model", "a model file path", self.model, fix)
        _validate.check_fields(self)  # the bounds declared beside the fields
        for name, what, fix in (
            ("gazes", "gazes", "e.g. --gazes 0.2,0.35,0.5,0.65,0.8"),
            ("eye_grid", "eye positions", "e.g. --eye-grid 0.3,0.5,0.7"),
        ):
            values = getattr(self, name)
            if len(set(values)) < 3:
                raise _validate.fail(name, f"at least 3 distinct {what}", list(values), fix)
            object.__setattr__(self, name, tuple(sorted(set(values))))
        if 0 < self.n_probe < 5:
            raise _validate.fail("n_probe", "0 or at least 5", self.n_probe, "e.g. 61")
        if any(v == 0.0 for v in self.body_slope):
            raise _validate.fail("body_slope", "nonzero", list(self.body_slope), "e.g. -1")
        axes = self.gaze_axes  # the model's dimension is checked where it is loaded
        check_gaze_axes(axes, len(axes), "e.g. --gaze-axes 1,0")
        _validate.boolean("nwb", self.nwb)


# -- the result: its JSON form, table and figure ---------------------------------------------------


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

    @classmethod
    def from_dict(cls, data: object) -> PhysiologyResult:
        """The result a :meth:`to_dict` wrote (``result.json``): its settings as the config
        (``tuning_units`` at its default: the file does not hold it), the time, and the rest
        as the recording (the verdict is computed again)."""
        obj = dict(as_object(data))
        settings = tuples(as_object(obj.pop("settings"), "settings"))
        seconds = float(obj.pop("seconds"))
        obj.pop("body_centred")
        return cls(PhysiologyConfig(**settings), obj, seconds)

    def body_centred(self) -> bool:
        """Whether the trained map's median reference-frame index is at least
        :data:`BODY_CENTRED`."""
        med = self.data["trained"]["median_reference_frame_index"]
        return med is not None and med >= BODY_CENTRED

    def settings(self) -> dict[str, object]:
        """The config's fields but the tuning units."""
        return {k: v for k, v in dataclasses.asdict(self.config).items() if k != "tuning_units"}

    def table(self) -> str:
        """The medians of both maps and the comparison."""
        rows = render(COLUMNS, [{"map": k, **self.data[k]} for k in ("trained", "random_start")])
        c = self.data["comparison"]
        if c["ks"] is not None:
            n = f"(n = {c['n'][0]}, {c['n'][1]})"
            rows.append(f"trained vs random start: KS {c['ks']:.3f}, p = {c['p_value']:.2g} {n}")
        rows.append(self._monkey_line())
        return "\n".join(rows)

    def _monkey_line(self) -> str:
        m = self.data["monkey"]
        share = m["gain_modulated_share"]
        idx, r2 = m["reference_frame_index"]["median"], m["gain_r2"]["median"]
        shifted, every = m["displacement_index"]["median"], m["reference_frame_index_all"]["median"]
        left = ", ".join(f"{v} {k.replace('_', ' ')}" for k, v in m["left_out"].items())
        return (
            f"monkey protocol ({len(m['fixations'])} fixations, {m['n_retina']} stimuli per "
            f"axis): {m['admitted']} of {m['units']} units admitted (left out: {left}); "
            + (f"gain-modulated {100 * share:.0f} %" if share is not None else "no unit admitted")
            + (f", planar-fit R^2 median {r2:.2f}" if r2 is not None else "")
            + (f", reference-frame index median {idx:.2f}" if idx is not None else "")
            + (f" (by cross-correlation {shifted:.2f})" if shifted is not None else "")
            + (f" (every unit: {every:.2f})" if every is not None else "")
        )

    def caption(self) -> str:
        """The figure's caption, computed from the data."""
        t, s, c = self.data["trained"], self.data["random_start"], self.data["comparison"]

        def med(r: dict[str, object]) -> str:
            v = r["median_reference_frame_index"]
            return "no unit measured" if v is None else f"median {v:.2f}"

        criterion = f"not body-centred by the {BODY_CENTRED} criterion"
        verdict = "body-centred" if self.body_centred() else criterion
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
        out = Path(out_dir) / FIGURE
        fig = save_captioned(physiology_figure(self.to_dict()), out, self.caption(), dpi=110)
        nwb = self.data.get("nwb")
        return [fig, *([Path(out_dir) / nwb] if nwb else [])]


# -- the run: the recording of the model file and of its random start ------------------------------


NWB_FILE = "physiology.nwb"
"""The NWB file ``sigmapi physiology --nwb --out DIR`` writes into DIR."""


class RandomStart:
    """The map a model file's config starts from with the paper's random weights (uniform in
    ``[-init_scale, init_scale]``, ``ordering = "none"``), for the model's own seed."""

    def __init__(self, model: SigmaPiSOM) -> None:
        start = SigmaPiSOM(model.config.replace(ordering="none"), seed=model.seed_entropy)
        self.x_code, self.y_code = start.x_code, start.y_code
        self.map_shape, self.sampler = start.map_shape, start.sampler
        self.weights = start.initial_weights()

    def respond(self, x: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """``h_k = x^T W_k y`` ``(B, K)``."""
        k, nx, ny = self.weights.shape
        t = (self.weights.reshape(k * nx, ny) @ np.asarray(y).T).reshape(k, nx, -1)
        return np.asarray(np.einsum("bi,kib->bk", np.asarray(x), t))


def _tuning(model: Recordable, cfg: PhysiologyConfig, n_probe: int | None) -> dict[str, object]:
    """Tuning curves along retinal axis 0 of ``tuning_units`` units spread over the map (in
    2-D on the probe row through each unit's peak at the middle gaze)."""
    resp, probes = tuning_curves(model, cfg.gazes, 0, n_probe, (cfg.gaze_axes or (0,))[0])
    k = resp.shape[2]
    units = np.unique(np.linspace(0, k - 1, cfg.tuning_units + 2)[1:-1].round().astype(int))
    mid = len(cfg.gazes) // 2
    responses, positions = [], []
    for u in units:
        line = np.arange(probes.shape[0])
        if probes.shape[1] > 1:
            best = probes[np.argmax(resp[mid, :, u])]
            line = np.nonzero(np.all(probes[:, 1:] == best[1:], axis=1))[0]
        responses.append(resp[:, line, u].tolist())
        positions = probes[line, 0].tolist()
    gazes = list(cfg.gazes)
    return {"units": units.tolist(), "gazes": gazes, "responses": responses, "positions": positions}


def record_model(
    cfg: PhysiologyConfig, recording: dict[str, Any] | None = None
) -> dict[str, object]:
    """The trained map's and its random start's per-unit indices, their comparison, the
    tuning curves the figure draws and the monkey protocol (``monkey``,
    :func:`~sigmapi.analysis.monkey.monkey_protocol`); ``recording``, a dict, receives the
    model and the protocol's raw :func:`~sigmapi.analysis.monkey.fixation_protocol` (for the
    NWB file)."""
    path = Path(cfg.model)
    if not path.is_file():
        raise DataError(
            f"model {str(path)!r} is not a file; give a model file written by "
            "sigmapi train --out FILE"
        )
    model = load_model(path)
    n_probe = cfg.n_probe or None
    slope = cfg.body_slope or None
    axes = cfg.gaze_axes or None  # record() checks them against the model's axes
    trained = record(model, cfg.gazes, n_probe, slope, axes)
    start = record(RandomStart(model), cfg.gazes, n_probe, slope, axes)
    index = trained["reference_frame_index"]
    raw = fixation_protocol(model, cfg.eye_grid, cfg.n_retina)
    monkey = monkey_protocol(
        model, cfg.eye_grid, cfg.n_retina, slope, axes, responds=cfg.responds, recording=raw
    )
    if recording is not None:
        recording.update(model=model, fixation=raw)
    return {
        "model": str(path),
        "map_shape": list(model.map_shape),
        "relation": model.sampler.relation.name,
        "trained": trained,
        "random_start": start,
        "reference_frame_index": index,
        "comparison": compare_distributions(index, start["reference_frame_index"]),
        "tuning": _tuning(model, cfg, n_probe),
        "monkey": monkey,
    }


class PhysiologyExperiment(Experiment[PhysiologyConfig]):
    """Tuning curves, reference-frame indices and gain fields of every unit of a model file,
    against the same map's random start. The seeds are not used (the model file holds its
    own)."""

    name = "physiology"
    summary = "read a model file's units as an electrophysiologist: reference frame, gain fields"
    config_type = PhysiologyConfig
    seeds = (0,)
    default_out = None
    writes = (FIGURE, Path(FIGURE).with_suffix(".txt").name, NWB_FILE)

    def execute(self, config: PhysiologyConfig, run: Run) -> PhysiologyResult:
        start = time.perf_counter()
        if config.nwb and run.out is None:
            raise UsageError("--nwb writes physiology.nwb into --out; give --out DIR")
        if config.nwb:
            from sigmapi.nwb import pynwb_module

            pynwb_module()  # the extra's hint before the recording
        recording: dict[str, Any] = {}
        data = record_model(config, recording)
        if config.nwb and run.out is not None:
            from sigmapi.neurons.spiking import protocol_spikes
            from sigmapi.nwb import export_nwb

            export_nwb(
                recording["model"],
                Path(run.out) / NWB_FILE,
                physiology=data,
                fixation=recording["fixation"],
                model_path=config.model,
                force=True,
                spikes=protocol_spikes,
            )
            data["nwb"] = NWB_FILE
        return PhysiologyResult(config, data, time.perf_counter() - start)


PHYSIOLOGY = register(PhysiologyExperiment())


# -- the figure: from the JSON form (every mark in a legend, below its panel) ---------------------


def physiology_figure(result: dict[str, Any]) -> Figure:
    """Reference-frame index distributions (trained map against its random start), tuning
    curves of three units at every gaze, and the gain-field fits; below, the monkey protocol
    beside the published numbers (where the result has one)."""
    import matplotlib.pyplot as plt  # only when drawing

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
    gazes = ", ".join(f"{g:g}" for g in curves["gazes"])
    ax.set_title(f"tuning curves at gazes {gazes} (darker: larger)")
    ax.legend(fontsize=8, **BELOW)

    ax = axes[2]
    for key, label in (("trained", "trained map"), ("random_start", "random start")):
        mod = [v for v in result[key]["peak_modulation"] if v is not None]
        fits = zip(result[key]["gain_r2"], result[key]["gain_slope"], strict=True)
        pairs = [(a, b) for a, b in fits if a is not None and b is not None]
        text = f"{np.median(mod):.2f}" if mod else "-"
        r2, slope = [a for a, _ in pairs], [b for _, b in pairs]
        ax.scatter(r2, slope, s=10, alpha=0.6, label=f"{label}: peak modulation median {text}")
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
    for p in [p for p in m["published"] if p["measure"] == "gain_modulated_share"]:
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
        alpha, hatch = (0.75, None) if ok else (0.35, "//")
        label = who if ok else f"{who}, not verified against the paper"
        ax.barh(y, v, color=colour, alpha=alpha, hatch=hatch, label=label)
        ax.text(min(v, 0.98), y, f" {100 * v:.0f} %", va="center", ha="right", fontsize=7)
    ax.set_yticks(ys, [b[0] for b in bars], fontsize=7)
    ax.invert_yaxis()
    ax.set_xlim(0, 1)
    ax.set_xlabel("share of units with an eye-position effect")
    title = f"eye-position effect: ANOVA over the fixations, p < {m['alpha']:g}\n"
    ax.set_title(title + "(hatched: not verified against the paper)", fontsize=8)
    legend_once(ax, fontsize=7, **BELOW)

    ax = axes[1]
    per = m["per_unit"]
    adm = [v for v in per["reference_frame_index"] if v is not None]
    every = zip(per["reference_frame_index_all"], per["admitted"], strict=True)
    out = [v for v, a in every if v is not None and not a]
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
