"""A trained map as a recorded brain area in an NWB file (Neurodata Without Borders, the DANDI
archive's format): :func:`export_nwb`, ``sigmapi export MODEL --format nwb --out FILE.nwb``
and ``sigmapi physiology MODEL --nwb --out DIR``.

The file holds what :mod:`sigmapi.analysis.monkey`'s protocol records
(docs/guide/neurons.md):

- the **trials** table: one trial per condition of the protocol, a fixation of the eye grid
  with a stimulus at a point of the retinal grid: columns ``retinal_position`` and ``gaze``
  (one value per axis, fractions of the axis), ``body_position`` (the z of that view pair,
  the model's relation ``forward(x, y)``), ``fixation`` and ``stimulus`` (the indices into
  the two grids); trials are 1 s apart, each 0.5 s long (the protocol's counting window);
- the **rates**: processing module ``misc``, TimeSeries ``responses``
  ``(trials, units)``, the map's responses ``h = x^T W y`` to each trial (arbitrary units;
  timestamps the trials' starts), and ``rates`` in Hz as the protocol scales them (the unit's
  best response at 100 Hz);
- the **units** table: one row per map unit, ``grid_position`` (its index on the map),
  ``preferred_z``, ``admitted`` (by the protocol), ``reference_frame_index`` (NaN where not
  admitted), ``displacement_index`` (the same by cross-correlation), ``gain_slope``,
  ``gain_r2`` (planarity of the gain field), ``gain_p_value`` and
  ``gain_modulated``, and ``spike_times``: the spikes sigmapi's spiking deployment produced
  in each trial's window where it ran (a :class:`TrialSpikes` passed in: ``sigmapi export``
  and ``sigmapi physiology --nwb`` run
  :func:`sigmapi.neurons.spiking.protocol_spikes` on the protocol's trials where they fit
  its budget), else Poisson spikes drawn at the unit's rate in each trial's window; the
  column's and the table's descriptions, and ``spike_times`` in the provenance, say which;
- the **subject**: a simulated area (``species`` ``"in silico"``, sex ``"U"``, born when its
  model file was written);
- the **provenance**: ``source_script`` (``sigmapi <version>``), and in ``notes`` a JSON
  object with the sigmapi version, the model's config, seed, iterations and the SHA-256 of
  the model file (or of its weights, for a model not read from a file).

pynwb is imported only here, when a file is made (the ``nwb`` extra); the file is written
to a temp file beside the target and renamed (:func:`sigmapi.io.atomic_write`).
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from sigmapi._version import __version__
from sigmapi.analysis.monkey import PEAK_RATE, WINDOW, fixation_protocol, monkey_protocol
from sigmapi.errors import UsageError
from sigmapi.io import atomic_write_bytes, digest
from sigmapi.model.som import SigmaPiSOM, load_model

if TYPE_CHECKING:
    from pynwb import NWBFile

__all__ = ["PERIOD", "TrialSpikes", "export_nwb", "nwb_file", "protocol_trials", "pynwb_module"]

PERIOD = 1.0
"""Seconds from one trial's start to the next's."""


@dataclass(frozen=True)
class TrialSpikes:
    """Spikes a simulation produced in the protocol's trials (in the file's trial order,
    :func:`protocol_trials`): one entry per spike, ``trial`` and ``unit`` its indices and
    ``time`` its time (s) from the trial's start, within the trial's window; ``source``:
    what produced them, a phrase for the descriptions (e.g. "sigmapi's spiking deployment
    ..."); ``settings``: that run's settings, for the provenance."""

    trial: NDArray[np.int64]
    unit: NDArray[np.int64]
    time: NDArray[np.float64]
    source: str
    settings: dict[str, object]


Spikes = TrialSpikes | Callable[[SigmaPiSOM, dict[str, Any]], TrialSpikes | None] | None
"""What :func:`nwb_file` takes as ``spikes``."""


def protocol_trials(fixation: dict[str, Any]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """The file's trials as indices ``(fixation, stimulus)`` into a
    :func:`~sigmapi.analysis.monkey.fixation_protocol` recording's ``eyes`` and ``stimuli``:
    trial ``t`` is fixation ``t // P`` and stimulus ``t % P`` (``P`` stimuli)."""
    n_e, n_p = len(fixation["eyes"]), len(fixation["stimuli"])
    return np.repeat(np.arange(n_e), n_p), np.tile(np.arange(n_p), n_e)


_NEEDS = "install the nwb extra: pip install 'sigmapi[nwb]'"


def pynwb_module() -> ModuleType:
    """The pynwb package, or a :class:`~sigmapi.errors.UsageError` with the one-line hint."""
    try:
        import pynwb
    except ImportError:
        raise UsageError(f"writing NWB files needs the pynwb package; {_NEEDS}") from None
    return pynwb


def _file_digest(path: str | Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _provenance(model: SigmaPiSOM, model_path: str | Path | None) -> dict[str, object]:
    cfg = model.config
    fields = {k: getattr(cfg, k) for k in cfg.__dataclass_fields__}
    return {
        "sigmapi_version": __version__,
        "model_file": None if model_path is None else str(model_path),
        "model_sha256": _file_digest(model_path) if model_path is not None else None,
        "weights_sha256": digest(np.asarray(model.weights_)),
        "seed": cfg.seed,
        "iterations": int(model.t_),
        "config": json.loads(json.dumps(fields, default=list)),
    }


def nwb_file(
    model: SigmaPiSOM,
    *,
    physiology: dict[str, Any] | None = None,
    fixation: dict[str, Any] | None = None,
    model_path: str | Path | None = None,
    spikes: Spikes = None,
) -> NWBFile:
    """The ``pynwb.NWBFile`` of a fitted ``model`` (module docstring).

    ``fixation`` and ``physiology``: a :func:`~sigmapi.analysis.monkey.fixation_protocol`
    recording and the ``sigmapi physiology`` result (its ``monkey`` entry) made from it, as
    ``sigmapi physiology --nwb`` passes them; else the protocol runs here with its defaults.
    ``model_path``: the file the model was read from (its digest goes into the provenance).
    ``spikes``: the units' spike times in the trials of ``fixation``, or a function of the
    model and ``fixation`` that gives them or None
    (:func:`sigmapi.neurons.spiking.protocol_spikes`); where none, Poisson draws at the
    units' rates.
    """
    pynwb = pynwb_module()
    from hdmf.backends.hdf5 import H5DataIO
    from hdmf.common import VectorData, VectorIndex
    from pynwb.epoch import TimeIntervals
    from pynwb.file import Subject
    from pynwb.misc import Units

    if fixation is None:
        fixation = fixation_protocol(model)
    monkey = (physiology or {}).get("monkey") or monkey_protocol(model, recording=fixation)
    if callable(spikes):
        spikes = spikes(model, fixation)
    eyes, stimuli, resp = fixation["eyes"], fixation["stimuli"], fixation["responses"]
    n_e, n_p, k = resp.shape
    prov = _provenance(model, model_path)
    prov["spike_times"] = (
        {"source": "poisson", "seed": int(monkey["seed"])}
        if spikes is None
        else {"source": "spiking", "settings": spikes.settings}
    )
    ident = prov["model_sha256"] or prov["weights_sha256"]
    now = datetime.now(UTC)
    # the map's "birth": when its model file was written (the end of its training)
    born = now if model_path is None else datetime.fromtimestamp(os.stat(model_path).st_mtime, UTC)
    nwb = pynwb.NWBFile(
        session_description=(
            "A Sigma-Pi self-organizing map (sigmapi) recorded as a brain area: every unit's "
            "response to stimuli at a grid of retinal positions while the eyes fixate a grid "
            "of eye positions (the gain-field studies' protocol)"
        ),
        identifier=f"sigmapi-{str(ident)[:32]}",
        session_start_time=now,
        experiment_description=monkey["test"],
        source_script=f"sigmapi {__version__}",
        source_script_file_name="sigmapi",
        notes=json.dumps(prov),
        keywords=["sigma-pi", "self-organizing map", "gain field", "reference frame"],
        subject=Subject(
            subject_id=f"sigmapi-map-seed-{model.config.seed}",
            description="a simulated brain area: a Sigma-Pi self-organizing map trained by "
            "sigmapi, no animal",
            species="in silico",
            sex="U",
            date_of_birth=born,
        ),
    )
    rel = model.sampler.relation
    cond_e, cond_p = protocol_trials(fixation)
    x, y = stimuli[cond_p], eyes[cond_e]
    z = np.asarray(rel.forward(x, y), dtype=np.float64)
    starts = np.arange(n_e * n_p) * PERIOD
    columns = {
        "retinal_position": ("stimulus position on the retina, per axis (fraction of the axis)", x),
        "gaze": ("eye position, per gaze axis (fraction of the axis)", y),
        "body_position": ("body-centred position z = forward(retinal_position, gaze), per axis",
                          z),
        "fixation": ("index of the eye position in the protocol's eye grid", cond_e),
        "stimulus": ("index of the stimulus in the protocol's retinal grid", cond_p),
    }  # fmt: skip
    nwb.trials = TimeIntervals(
        name="trials",
        description="the protocol's conditions: a stimulus at a retinal position while the "
        "eyes fixate a gaze; one trial each",
        columns=[
            VectorData(name="start_time", description="trial start (s)", data=starts),
            VectorData(name="stop_time", description="trial stop (s)", data=starts + WINDOW),
            *(VectorData(name=n, description=d, data=v) for n, (d, v) in columns.items()),
        ],
    )
    per = monkey["per_unit"]
    top = np.maximum(resp.max(axis=(0, 1)), 1e-300)
    flat = resp.reshape(n_e * n_p, k)
    rates = PEAK_RATE * np.maximum(flat, 0.0) / top
    module = nwb.create_processing_module(
        name="misc", description="the map's responses to the protocol's trials (sigmapi)"
    )
    for name, data, unit, text in (
        ("responses", flat, "a.u.",
         "response h = x^T W y of every unit (columns) to each trial (rows, at the trials' "
         "starts)"),
        ("rates", rates, "Hz",
         f"responses as firing rates: each unit's best response at {PEAK_RATE:g} Hz, "
         "negative responses at 0; one row per trial"),
    ):  # fmt: skip
        module.add(
            pynwb.TimeSeries(
                name=name,
                data=H5DataIO(data, compression="gzip"),
                unit=unit,
                starting_time=0.0,
                rate=1.0 / PERIOD,
                description=text,
            )
        )

    def num(key: str) -> np.ndarray:
        return np.asarray([np.nan if v is None else v for v in per[key]], dtype=np.float64)

    trains, spike_text = _spike_trains(spikes, rates, starts, int(monkey["seed"]))
    spike_times = VectorData(
        name="spike_times",
        description=f"{spike_text} (s)",
        data=H5DataIO(np.concatenate(trains), compression="gzip"),
    )
    pref = np.asarray(
        [[np.nan if v is None else v for v in row] for row in per["preferred_z"]], np.float64
    )
    unit_columns = (
        ("grid_position", "the unit's index on the map, per map axis",
         np.stack(np.unravel_index(np.arange(k), model.map_shape), axis=1).astype(np.int64)),
        ("preferred_z", "body position z at the receptive field's centre at the central "
         "fixation, per axis", pref),
        ("admitted", "whether the protocol admits the unit (field mapped at >= 3 eye "
         "positions along every axis)", np.asarray(per["admitted"], dtype=bool)),
        ("reference_frame_index", "receptive-field shift with the eye over a body-centred "
         "field's (0 eye-centred, 1 body-centred); NaN where not admitted",
         num("reference_frame_index")),
        ("displacement_index", "the same by cross-correlating the field's maps between "
         "fixations (Avillac et al. 2005); NaN where not admitted",
         num("displacement_index")),
        ("gain_slope", "slope of the planar gain-field fit, |b| over the mean rate",
         num("gain_slope")),
        ("gain_r2", "R^2 of the planar gain-field fit (planarity)", num("gain_r2")),
        ("gain_p_value", "p-value of the eye-position effect (one-way ANOVA)",
         num("gain_p_value")),
        ("gain_modulated", "eye-position effect at p < 0.05",
         np.asarray(per["gain_modulated"], dtype=bool)),
    )  # fmt: skip
    nwb.units = Units(
        name="units",
        description=(
            "the map's units, one row each, read by the monkey protocol "
            f"(sigmapi.analysis.monkey). spike_times: {spike_text}"
        ),
        columns=[
            spike_times,
            VectorIndex(
                name="spike_times_index",
                data=np.cumsum([len(t) for t in trains]).astype(np.int64),
                target=spike_times,
            ),
            *(VectorData(name=n, description=d, data=v) for n, d, v in unit_columns),
        ],
    )
    return nwb


def _spike_trains(
    spikes: TrialSpikes | None, rates: NDArray[np.float64], starts: NDArray[np.float64], seed: int
) -> tuple[list[NDArray[np.float64]], str]:
    """Each unit's sorted spike times (s, the file's clock) and the phrase that says what they
    are: ``spikes`` where given, else Poisson draws at ``rates`` ``(trials, units)``."""
    k = rates.shape[1]
    if spikes is not None:
        times = starts[spikes.trial] + spikes.time
        order = np.lexsort((times, spikes.unit))
        unit, times = spikes.unit[order], times[order]
        bounds = np.searchsorted(unit, np.arange(k + 1))
        trains = [times[bounds[u] : bounds[u + 1]] for u in range(k)]
        return trains, f"the spikes {spikes.source} produced in each trial's window"
    rng = np.random.default_rng(seed)
    counts = rng.poisson(rates * WINDOW)  # (trials, units)
    trains = []
    for u in range(k):
        times = np.repeat(starts, counts[:, u]) + rng.uniform(0.0, WINDOW, int(counts[:, u].sum()))
        trains.append(np.sort(times))
    text = (
        f"Poisson spikes drawn at the unit's rate in each trial's {WINDOW:g} s window (seed "
        f"{seed}), a model of a recording: sigmapi's spiking deployment "
        "(sigmapi.neurons.spiking) was not run for this file"
    )
    return trains, text


def export_nwb(
    model: SigmaPiSOM | str | Path,
    out: str | Path,
    *,
    physiology: dict[str, Any] | None = None,
    fixation: dict[str, Any] | None = None,
    model_path: str | Path | None = None,
    force: bool = False,
    spikes: Spikes = None,
) -> Path:
    """Write the NWB file of ``model`` (a fitted model or a model file) to ``out``,
    atomically; returns the path. Refuses an existing ``out`` unless ``force``
    (:class:`~sigmapi.errors.UsageError`); ``physiology``, ``fixation``, ``model_path``,
    ``spikes``: as :func:`nwb_file` takes them."""
    target = Path(out)
    if target.exists() and not force:
        raise UsageError(f"out {str(target)!r} exists; pass force=True (--force) to overwrite it")
    pynwb = pynwb_module()  # before reading a large model
    if not isinstance(model, SigmaPiSOM):
        model_path = model if model_path is None else model_path
        model = load_model(model)
    nwb = nwb_file(
        model, physiology=physiology, fixation=fixation, model_path=model_path, spikes=spikes
    )
    import h5py

    folder = target.parent if str(target.parent) else Path(".")
    # HDF5 writes by path (and reads as it writes): a temp file named as atomic_write names
    # its own (so that one a killed write left is cleared as stale), whose bytes then go
    # through atomic_write's rename with the user's umask
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=folder)
    os.close(fd)
    try:
        with h5py.File(tmp, "w") as h5, pynwb.NWBHDF5IO(file=h5, mode="w") as io:
            io.write(nwb)
        data = Path(tmp).read_bytes()
    finally:
        Path(tmp).unlink(missing_ok=True)
    return atomic_write_bytes(target, data)
