"""What ``sigmapi physiology`` records: the model file's map and its random start."""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi.analysis.monkey import fixation_protocol, monkey_protocol
from sigmapi.analysis.physiology import compare_distributions, record, tuning_curves
from sigmapi.codes import PopulationCode
from sigmapi.errors import DataError, UsageError
from sigmapi.executor import Executor
from sigmapi.experiments.base import Experiment, register
from sigmapi.model.som import SigmaPiSOM, load_model
from sigmapi.progress import Progress
from sigmapi.tasks import TwoViewSampler

from .config import PhysiologyConfig
from .result import PhysiologyResult

__all__ = ["NWB_FILE", "PHYSIOLOGY", "PhysiologyExperiment", "RandomStart", "record_model"]

NWB_FILE = "physiology.nwb"
"""The NWB file ``sigmapi physiology --nwb --out DIR`` writes into DIR."""


class RandomStart:
    """The map a model file's config starts from with the paper's random weights (uniform in
    ``[-init_scale, init_scale]``, ``ordering = "none"``), for the model's own seed."""

    def __init__(self, model: SigmaPiSOM) -> None:
        self.model = SigmaPiSOM(model.config.replace(ordering="none"), seed=model.seed_entropy)
        self.weights = self.model.initial_weights()

    @property
    def x_code(self) -> PopulationCode:
        return self.model.x_code

    @property
    def y_code(self) -> PopulationCode:
        return self.model.y_code

    @property
    def map_shape(self) -> tuple[int, ...]:
        return self.model.map_shape

    @property
    def sampler(self) -> TwoViewSampler:
        return self.model.sampler

    def respond(self, x: Any, y: Any) -> NDArray[np.float64]:
        """``h_k = x^T W_k y`` ``(B, K)``."""
        k, nx, ny = self.weights.shape
        t = (self.weights.reshape(k * nx, ny) @ np.asarray(y).T).reshape(k, nx, -1)
        return np.asarray(np.einsum("bi,kib->bk", np.asarray(x), t))


def _tuning(model: Any, cfg: PhysiologyConfig, n_probe: int | None) -> dict[str, Any]:
    """Tuning curves along retinal axis 0 of ``tuning_units`` units spread over the map (in
    2-D on the probe row through each unit's peak at the middle gaze)."""
    resp, probes = tuning_curves(model, cfg.gazes, 0, n_probe, (cfg.gaze_axes or (0,))[0])
    k = resp.shape[2]
    units = np.unique(np.linspace(0, k - 1, cfg.tuning_units + 2)[1:-1].round().astype(int))
    mid = len(cfg.gazes) // 2
    out: dict[str, Any] = {"units": units.tolist(), "gazes": list(cfg.gazes), "responses": []}
    for u in units:
        line = np.arange(probes.shape[0])
        if probes.shape[1] > 1:
            best = probes[np.argmax(resp[mid, :, u])]
            line = np.nonzero(np.all(probes[:, 1:] == best[1:], axis=1))[0]
        out["responses"].append(resp[:, line, u].tolist())
        out["positions"] = probes[line, 0].tolist()
    return out


def record_model(cfg: PhysiologyConfig, recording: dict[str, Any] | None = None) -> dict[str, Any]:
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
        "reference_frame_index": trained["reference_frame_index"],
        "comparison": compare_distributions(
            trained["reference_frame_index"], start["reference_frame_index"]
        ),
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
    writes = ("physiology.png", "physiology.txt", NWB_FILE)

    def run(
        self,
        config: PhysiologyConfig,
        *,
        seeds: Sequence[int],
        out: Path | None = None,
        executor: Executor | None = None,
        progress: Progress | None = None,
    ) -> PhysiologyResult:
        start = time.perf_counter()
        if config.nwb and out is None:
            raise UsageError("--nwb writes physiology.nwb into --out; give --out DIR")
        if config.nwb:
            from sigmapi.nwb import pynwb_module

            pynwb_module()  # the extra's hint before the recording
        recording: dict[str, Any] = {}
        data = record_model(config, recording)
        if config.nwb and out is not None:
            from sigmapi.nwb import export_nwb

            export_nwb(
                recording["model"],
                Path(out) / NWB_FILE,
                physiology=data,
                fixation=recording["fixation"],
                model_path=config.model,
                force=True,
            )
            data["nwb"] = NWB_FILE
        return PhysiologyResult(config, data, time.perf_counter() - start)


PHYSIOLOGY = register(PhysiologyExperiment())
