"""The map read as an electrophysiologist reads it (sigmapi.analysis.physiology) and
`sigmapi physiology MODEL`."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sigmapi import SigmaPiSOM
from sigmapi.analysis.physiology import (
    body_slope,
    compare_distributions,
    gain_fields,
    record,
    reference_frame_index,
)
from sigmapi.codes import PopulationCode
from sigmapi.errors import ConfigError
from sigmapi.experiments.physiology.run import PhysiologyConfig, PhysiologyResult
from sigmapi.tasks import TwoViewSampler


class Constructed:
    """Three units with Gaussian fields of width 0.06 centred at 0.35, 0.5, 0.65: of the retinal
    position (``frame="eye"``) or of ``z = (x + y) / 2`` (``frame="body"``); ``gain``: a
    planar gain over the gaze, ``1 + gain * y``."""

    def __init__(self, frame: str, gain: float = 0.0, ndim: int = 1, crossed: bool = False) -> None:
        shape = (15,) * ndim
        self.x_code, self.y_code = PopulationCode(shape), PopulationCode(shape)
        self.map_shape = (3,)
        self.sampler = TwoViewSampler("mean", self.x_code, self.y_code)
        self.frame, self.gain, self.crossed = frame, gain, crossed

    def respond(self, x, y):
        px, py = self.x_code.decode(x), self.y_code.decode(y)
        if self.crossed:  # gaze axis 1 moves the fields along retinal axis 0 and vice versa
            py = py[:, ::-1]
        pos = px if self.frame == "eye" else (px + py) / 2.0
        centres = np.array([0.35, 0.5, 0.65])  # fully mapped at >= 3 gazes
        d2 = ((pos[:, None, :] - centres[None, :, None]) ** 2).sum(axis=2)
        return np.exp(-d2 / (2 * 0.06**2)) * (1.0 + self.gain * py.sum(axis=1))[:, None]


@pytest.mark.parametrize("ndim", [1, 2])
def test_an_eye_centred_unit_scores_0_and_a_body_centred_unit_1(ndim):
    eye = reference_frame_index(Constructed("eye", ndim=ndim))["reference_frame_index"]
    body = reference_frame_index(Constructed("body", ndim=ndim))["reference_frame_index"]
    assert body_slope(Constructed("body")) == pytest.approx(-1.0)
    assert np.all(np.abs(eye) < 0.05), eye
    assert np.all(np.abs(body - 1.0) < 0.05), body


def test_a_field_the_retinas_edge_cuts_off_does_not_count():
    # body-centred unit at z = 0.35: field at x = 0.7 - gaze, half-maximum radius 0.14;
    # at gazes 0.65 and 0.8 (x = 0.05, -0.1) the edge cuts it, at 0.2-0.5 it is fully mapped
    r = reference_frame_index(Constructed("body"))
    assert r["valid_gazes"][0][0] == 3 and abs(r["reference_frame_index"][0] - 1.0) < 0.05


def test_a_world_of_its_own_geometry_passes_its_body_slope():
    body = Constructed("body")
    twice = reference_frame_index(body, slope=[-2.0])["reference_frame_index"]
    assert np.allclose(twice, 0.5, atol=0.03)  # the field moves half as far as such a body's
    assert record(body, slope=[-2.0])["body_slope"] == [-2.0]
    with pytest.raises(ConfigError, match="body_slope"):
        reference_frame_index(body, slope=[0.0])
    with pytest.raises(ConfigError, match="body_slope"):
        PhysiologyConfig(model="m.npz", body_slope=(0.0,))


def test_a_body_whose_gaze_axes_come_crosswise_names_them():
    crossed = Constructed("body", ndim=2, crossed=True)
    wrong = reference_frame_index(crossed)["reference_frame_index"]
    right = reference_frame_index(crossed, gaze_axes=[1, 0])
    assert np.all(np.abs(wrong) < 0.05), wrong  # the same axis never moves the field
    assert np.all(np.abs(right["reference_frame_index"] - 1.0) < 0.05), right
    assert record(crossed, gaze_axes=[1, 0])["gaze_axes"] == [1, 0]
    assert record(Constructed("body", ndim=2))["gaze_axes"] == [0, 1]
    for bad in ([0, 0], [1], [0, 2]):
        with pytest.raises(ConfigError, match="gaze_axes"):
            reference_frame_index(crossed, gaze_axes=bad)
    with pytest.raises(ConfigError, match="gaze_axes"):
        PhysiologyConfig(model="m.npz", gaze_axes=(1, 1))


def test_gain_fields_see_a_planar_gain_on_a_fixed_field_and_none_on_a_moving_one():
    gf = gain_fields(Constructed("eye", gain=1.0))
    assert np.all(gf["gain_r2"] > 0.99)
    assert np.allclose(gf["peak_modulation"], (1.8 - 1.2) / (1.8 + 1.2), atol=0.01)  # gazes .2-.8
    flat = gain_fields(Constructed("body"))
    assert np.all(flat["peak_modulation"] < 0.05)


def test_distributions_compare_by_kolmogorov_smirnov():
    same = compare_distributions([0.1, 0.2, 0.3], [0.1, 0.2, 0.3])
    assert same["ks"] == 0.0 and same["p_value"] == 1.0
    apart = compare_distributions(list(np.linspace(0, 0.2, 30)), [None, *np.linspace(0.9, 1, 30)])
    assert apart["ks"] == 1.0 and apart["p_value"] < 1e-6 and apart["n"] == [30, 30]


def test_a_trained_map_is_body_centred_and_its_random_start_is_not(tmp_path):
    model = SigmaPiSOM(map_shape=(9,), x_shape=(9,), y_shape=(9,), iterations=20000,
                       ordering="crossview", seed=0).fit()  # fmt: skip
    r = record(model)
    assert r["median_reference_frame_index"] > 0.85 and len(r["reference_frame_index"]) == 9
    path = tmp_path / "m.npz"
    model.save(path)
    out = subprocess.run(
        [sys.executable, "-m", "sigmapi.cli", "physiology", str(path), "--json", "--quiet",
         "--out", str(tmp_path / "p")],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["reference_frame_index"] == r["reference_frame_index"]
    assert data["comparison"]["ks"] > 0.5 and data["body_centred"] in (True, False)
    back = PhysiologyResult.from_dict(data)  # the file reads back: the same JSON, table
    assert back.to_dict() == data and "trained vs random start" in back.table()
    assert (tmp_path / "p" / "physiology.png").is_file()
    # the wrote line lists every file the command wrote, the caption too
    wrote = out.stderr.strip().splitlines()[-1].split("sigmapi physiology: wrote ")[1]
    files = {p.name for p in (tmp_path / "p").iterdir() if not p.name.startswith(".")}
    assert sorted(Path(f).name for f in wrote.split(", ")) == sorted(files)
    assert files == {"physiology.png", "physiology.txt", "result.json"}
    missing = subprocess.run(
        [sys.executable, "-m", "sigmapi.cli", "physiology", str(tmp_path / "none.npz")],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert missing.returncode == 2 and "none.npz" in missing.stderr
    assert "Traceback" not in missing.stderr
