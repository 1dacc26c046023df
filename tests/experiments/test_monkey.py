"""The gain-field studies' protocol (sigmapi.analysis.monkey), the NWB file (sigmapi.nwb) and
the commands that make them (`sigmapi physiology`, `sigmapi export --format nwb`)."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import subprocess
import sys

import numpy as np
import pytest

from sigmapi import SigmaPiSOM
from sigmapi.analysis.monkey import (
    ALPHA,
    PUBLISHED,
    anova_oneway,
    fixation_protocol,
    monkey_protocol,
)
from sigmapi.codes import PopulationCode
from sigmapi.errors import ConfigError, UsageError
from sigmapi.tasks import TwoViewSampler


class Fields:
    """Units with Gaussian fields (width 0.06) at 0.4, 0.5, 0.6 of the retinal position
    (``frame="eye"``) or of ``z = (x + y) / 2`` (``"body"``), times ``1 + gain * gaze``."""

    def __init__(self, frame: str, gain: float = 0.0, ndim: int = 1) -> None:
        self.x_code, self.y_code = PopulationCode((15,) * ndim), PopulationCode((15,) * ndim)
        self.map_shape = (3,)
        self.sampler = TwoViewSampler("mean", self.x_code, self.y_code)
        self.frame, self.gain = frame, gain

    def respond(self, x, y):
        px, py = self.x_code.decode(x), self.y_code.decode(y)
        pos = px if self.frame == "eye" else (px + py) / 2.0
        d2 = ((pos[:, None, :] - np.array([0.4, 0.5, 0.6])[None, :, None]) ** 2).sum(axis=2)
        return np.exp(-d2 / (2 * 0.06**2)) * (1.0 + self.gain * py.sum(axis=1))[:, None]


def test_the_anova_is_scipys():
    stats = pytest.importorskip("scipy.stats")
    rng = np.random.default_rng(3)
    for shape, lam in (((5, 8), 4.0), ((9, 8), 30.0), ((3, 20), 0.7)):
        g = rng.poisson(lam, shape).astype(float)
        f, p = anova_oneway(g)
        want = stats.f_oneway(*g)
        assert f == pytest.approx(want.statistic, rel=1e-9)
        assert p == pytest.approx(want.pvalue, rel=1e-7, abs=1e-12)
    assert anova_oneway(np.ones((4, 5))) == (pytest.approx(np.nan, nan_ok=True), 1.0)


@pytest.mark.parametrize("ndim", [1, 2])
def test_an_eye_centred_gain_field_and_a_body_centred_field(ndim):
    eye = monkey_protocol(Fields("eye", gain=1.0, ndim=ndim), n_retina=31)
    body = monkey_protocol(Fields("body", ndim=ndim), n_retina=31)
    assert eye["admitted"] == 3 and body["admitted"] == 3
    assert np.allclose(eye["per_unit"]["reference_frame_index"], 0.0, atol=0.05)
    assert np.allclose(body["per_unit"]["reference_frame_index"], 1.0, atol=0.05)
    assert np.allclose(eye["per_unit"]["displacement_index"], 0.0, atol=0.05)
    assert np.allclose(body["per_unit"]["displacement_index"], 1.0, atol=0.05)
    # a planar gain 1 + gaze: modulated, and the plane fits it
    assert eye["gain_modulated_share"] == 1.0 and eye["gain_r2"]["median"] > 0.99
    # a body-centred field leaves the fixed retinal stimulus as the eyes move: modulated
    # too, but not planar (the response peaks at the central fixation)
    assert body["gain_modulated_share"] == 1.0 and body["gain_r2"]["median"] < 0.5
    flat = monkey_protocol(Fields("eye", gain=0.0, ndim=ndim), n_retina=31)
    assert flat["gain_modulated_share"] == 0.0  # no effect: p >= 0.05 on every unit
    assert all(p >= ALPHA for p in flat["per_unit"]["gain_p_value"])


def test_bad_settings_name_the_parameter():
    with pytest.raises(ConfigError, match="eye_grid"):
        monkey_protocol(Fields("eye"), eye_grid=(0.5, 0.5, 0.6))
    with pytest.raises(ConfigError, match="n_retina"):
        monkey_protocol(Fields("eye"), n_retina=2)
    with pytest.raises(ConfigError, match="responds"):
        monkey_protocol(Fields("eye"), responds=1.5)


def test_every_published_number_names_its_source_and_whether_it_was_verified():
    for p in PUBLISHED:
        assert p["source"].startswith("https://") and isinstance(p["verified"], bool)
        assert p["where"] and p["study"]
        if not p["verified"]:
            assert "not verified" in p["note"]


@pytest.fixture(scope="module")
def small_map(tmp_path_factory):
    model = SigmaPiSOM(map_shape=(9,), x_shape=(9,), y_shape=(9,), iterations=20000,
                       ordering="crossview", seed=0).fit()  # fmt: skip
    path = tmp_path_factory.mktemp("m") / "m.npz"
    model.save(path)
    return model, path


def _xcorr_shift(a, b):
    """The shift s (grid steps) with b[p + s] most like a[p] (Pearson over the overlap,
    |s| <= n // 2), refined by a parabola through the best and its neighbours."""
    n = len(a)
    shifts = list(range(-(n // 2), n // 2 + 1))
    c = []
    for s in shifts:
        p = np.arange(max(0, -s), n - max(0, s))
        u, v = a[p] - a[p].mean(), b[p + s] - b[p + s].mean()
        den = np.sqrt((u @ u) * (v @ v))
        c.append((u @ v) / den if den > 0 else -np.inf)
    i = int(np.argmax(c))
    if 0 < i < len(c) - 1 and c[i - 1] - 2 * c[i] + c[i + 1] < 0:
        return shifts[i] + 0.5 * (c[i - 1] - c[i + 1]) / (c[i - 1] - 2 * c[i] + c[i + 1])
    return float(shifts[i])


def _independent(model, eye_grid, n_retina, share):
    """The protocol's admission, reference-frame index and cross-correlation displacement
    index, recomputed in plain NumPy (1-D)."""
    eyes = np.asarray(eye_grid, dtype=float)
    stim = np.linspace(0.0, 1.0, n_retina)
    x = model.x_code.encode(stim[:, None])
    resp = np.stack(
        [model.respond(x, model.y_code.encode(np.full((n_retina, 1), e))) for e in eyes]
    )
    index, shifted = [], []
    for u in range(resp.shape[2]):
        best_any = resp[:, :, u].max()
        es, cs = [], []
        for i in range(len(eyes)):
            r = resp[i, :, u]
            peak, at = r.max(), stim[np.argmax(r)]
            w = np.maximum(r - peak / 2, 0) * (np.abs(stim - at) <= 0.1)
            cut = w[0] > 0 or w[-1] > 0
            if peak > 0 and peak >= share * best_any and not cut:
                es.append(eyes[i])
                cs.append((w * stim).sum() / w.sum())
        ok = len(set(es)) >= 3
        index.append(np.polyfit(es, cs, 1)[0] / -1.0 if ok else np.nan)
        at = [int(np.nonzero(eyes == e)[0][0]) for e in es]
        pairs = [
            _xcorr_shift(resp[i, :, u], resp[j, :, u]) / (n_retina - 1)
            / ((eyes[j] - eyes[i]) * -1.0)
            for i in at for j in at if j > i
        ]  # fmt: skip
        shifted.append(np.median(pairs) if ok else np.nan)
    return np.asarray(index), np.asarray(shifted)


def test_the_protocol_agrees_with_an_independent_recomputation(small_map):
    model, _ = small_map
    grid = (0.3, 0.4, 0.5, 0.6, 0.7)
    r = monkey_protocol(model, grid, 41, responds=0.25)
    want, want_shifted = _independent(model, grid, 41, 0.25)
    for key, ref in (("reference_frame_index", want), ("displacement_index", want_shifted)):
        got = np.array([np.nan if v is None else v for v in r["per_unit"][key]])
        assert np.array_equal(np.isfinite(got), np.isfinite(ref)), key
        assert np.allclose(got[np.isfinite(got)], ref[np.isfinite(ref)], atol=1e-9), key
    assert r["admitted"] == int(np.isfinite(want).sum()) > 0
    assert r["admitted"] + sum(r["left_out"].values()) == 9
    assert r["reference_frame_index"]["median"] > 0.8  # the map is body-centred


def test_the_nwb_file_reads_back_and_passes_the_inspector(small_map, tmp_path):
    pynwb = pytest.importorskip("pynwb")
    inspector = pytest.importorskip("nwbinspector")
    from sigmapi.nwb import export_nwb

    model, path = small_map
    out = export_nwb(path, tmp_path / "map.nwb")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["map.nwb"]  # no temp file left
    with pytest.raises(UsageError, match="exists"):
        export_nwb(path, out)
    rec = fixation_protocol(model)
    want = monkey_protocol(model, recording=rec)["per_unit"]
    with pynwb.NWBHDF5IO(str(out), "r") as io:
        f = io.read()
        units = f.units.to_dataframe()
        trials = f.trials.to_dataframe()
        resp = f.processing["misc"]["responses"].data[:]
        prov = json.loads(f.notes)
        assert f.source_script.startswith("sigmapi ")
    e, p, k = rec["responses"].shape
    assert len(units) == k == 9 and len(trials) == e * p
    assert np.array_equal(np.stack(trials["gaze"]), rec["eyes"][np.repeat(np.arange(e), p)])
    assert np.array_equal(np.stack(trials["retinal_position"]),
                          rec["stimuli"][np.tile(np.arange(p), e)])  # fmt: skip
    z = (np.stack(trials["retinal_position"]) + np.stack(trials["gaze"])) / 2
    assert np.allclose(np.stack(trials["body_position"]), z)
    assert np.array_equal(resp, rec["responses"].reshape(e * p, k))
    for col in ("reference_frame_index", "displacement_index", "gain_r2", "gain_slope",
                "gain_p_value"):  # fmt: skip
        w = np.array([np.nan if v is None else v for v in want[col]])
        assert np.array_equal(units[col].to_numpy(), w, equal_nan=True), col
    assert units["admitted"].tolist() == want["admitted"]
    assert np.stack(units["grid_position"]).ravel().tolist() == list(range(9))
    assert all(np.all(np.diff(t) >= 0) for t in units["spike_times"])
    assert prov["model_sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
    assert prov["seed"] == 0 and prov["config"]["map_shape"] == [9]
    found = list(inspector.inspect_nwbfile(nwbfile_path=str(out)))
    top = inspector.Importance.CRITICAL.value
    critical = [m for m in found if m.importance.value >= top]
    assert not critical, [m.message for m in critical]


def _read_units(path):
    import pynwb

    with pynwb.NWBHDF5IO(str(path), "r") as io:
        f = io.read()
        trains = [np.asarray(t) for t in f.units["spike_times"][:]]
        return (trains, f.units["spike_times"].target.description, f.units.description,
                json.loads(f.notes)["spike_times"], f.trials["start_time"].data[:])  # fmt: skip


def test_the_nwb_file_holds_the_spikes_the_spiking_deployment_produced(small_map, tmp_path):
    pytest.importorskip("pynwb")
    inspector = pytest.importorskip("nwbinspector")
    from sigmapi.neurons.spiking import protocol_spikes
    from sigmapi.nwb import export_nwb, protocol_trials

    model, path = small_map
    rec = fixation_protocol(model, (0.3, 0.5, 0.7), 11)
    got = protocol_spikes(model, rec)
    out = export_nwb(path, tmp_path / "s.nwb", fixation=rec, spikes=got)
    trains, text, table, prov, starts = _read_units(out)
    assert len(starts) == len(protocol_trials(rec)[0]) == 33
    assert np.all((got.time >= 0) & (got.time < 0.5)) and len(got.unit) > 100
    for u, train in enumerate(trains):  # every spike of the run, at its trial's start + time
        mine = got.unit == u
        assert np.array_equal(train, np.sort(starts[got.trial[mine]] + got.time[mine]))
    assert sum(len(t) for t in trains) == len(got.unit)
    assert text.startswith("the spikes sigmapi's spiking deployment")
    assert text.removesuffix(" (s)") in table
    assert "not run" not in table
    assert prov["source"] == "spiking" and prov["settings"]["inhibition"] == 0.25
    found = list(inspector.inspect_nwbfile(nwbfile_path=str(out)))
    top = inspector.Importance.CRITICAL.value
    assert not [m.message for m in found if m.importance.value >= top]
    # a map whose protocol does not fit the budget keeps the Poisson draw, and says so
    out = export_nwb(model, tmp_path / "p.nwb", fixation=rec,
                     spikes=lambda m, f: protocol_spikes(m, f, budget=1.0))  # fmt: skip
    trains, text, _, prov, _ = _read_units(out)
    assert text.startswith("Poisson") and "was not run" in text and prov["source"] == "poisson"
    assert sum(len(t) for t in trains) > 0


def test_the_protocols_spiking_network_is_the_one_sigmapi_neurons_deploys():
    from sigmapi.experiments.neurons.config import NeuronsConfig
    from sigmapi.neurons.spiking import PROTOCOL

    want = NeuronsConfig().spiking(PROTOCOL.peak_rate)
    assert PROTOCOL == dataclasses.replace(want, windows_ms=(500.0,))


def test_without_pynwb_one_line_names_the_extra(monkeypatch):
    from sigmapi.nwb import pynwb_module

    monkeypatch.setitem(sys.modules, "pynwb", None)
    with pytest.raises(UsageError, match=r"pip install 'sigmapi\[nwb\]'"):
        pynwb_module()


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "sigmapi.cli", *map(str, args)],
                          capture_output=True, text=True, check=False)  # fmt: skip


def test_the_commands_as_a_user_runs_them(small_map, tmp_path):
    pytest.importorskip("pynwb")
    _, path = small_map
    out = _cli("export", path, "--format", "nwb", "--out", tmp_path / "m.nwb")
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "m.nwb").stat().st_size > 0 and "wrote" in out.stderr
    assert _read_units(tmp_path / "m.nwb")[3]["source"] == "spiking"  # the deployment ran
    again = _cli("export", path, "--format", "nwb", "--out", tmp_path / "m.nwb")
    assert again.returncode == 2 and "--force" in again.stderr  # it exists
    again = _cli("export", path, "--format", "nwb", "--out", tmp_path / "m.nwb", "--force",
                 "--opset", "18")  # fmt: skip
    assert again.returncode == 2 and "--opset" in again.stderr and "Traceback" not in again.stderr
    run = _cli("physiology", path, "--json", "--quiet", "--nwb", "--out", tmp_path / "p",
               "--eye-grid", "0.3,0.5,0.7")  # fmt: skip
    assert run.returncode == 0, run.stderr
    data = json.loads(run.stdout)
    m = data["monkey"]
    assert m["eye_grid"] == [0.3, 0.5, 0.7] and len(m["fixations"]) == 3
    assert {"gain_modulated_share", "gain_r2", "reference_frame_index", "left_out",
            "published", "admitted"} <= set(m)  # fmt: skip
    assert data["reference_frame_index"] and data["nwb"] == "physiology.nwb"
    assert _read_units(tmp_path / "p" / "physiology.nwb")[3]["source"] == "spiking"
    assert (tmp_path / "p" / "physiology.png").is_file()
    bad = _cli("physiology", path, "--nwb")
    assert bad.returncode == 2 and "--out" in bad.stderr and "Traceback" not in bad.stderr
    bad = _cli("physiology", path, "--eye-grid", "0.5,0.5")
    assert bad.returncode == 2 and "eye_grid" in bad.stderr and "Traceback" not in bad.stderr
