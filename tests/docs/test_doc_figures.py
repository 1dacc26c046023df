"""Every figure in docs/ is the one ``python docs/make_figures.py`` made and recorded in
docs/figures.json, from inputs that still hold: a preset, a results file or a spec that
changed, a PNG replaced by hand, or a map that today's code no longer trains fails here."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

import sigmapi

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
sys.path.insert(0, str(DOCS))
import make_figures  # noqa: E402

RECORD = json.loads((DOCS / "figures.json").read_text("utf-8"))
FIX = "run python docs/make_figures.py NAME and commit the figure with docs/figures.json"


def test_every_figure_in_docs_is_made_by_the_script_and_recorded():
    pngs = sorted(p.stem for p in DOCS.glob("*.png"))
    assert pngs == sorted(make_figures.RECIPES), "a figure in docs/ that no recipe makes"
    assert sorted(RECORD) == pngs, f"figures without a record; {FIX}"
    for name in pngs:
        entry = RECORD[name]
        assert entry["command"] == make_figures.RECIPES[name].command, (name, FIX)
        digest = make_figures.sha256(DOCS / f"{name}.png")
        assert entry["png_sha256"] == digest, f"docs/{name}.png is not the recorded one; {FIX}"


@pytest.mark.parametrize("name", sorted(RECORD))
def test_the_recorded_inputs_still_hold(name):
    inputs = RECORD[name]["inputs"]
    for source in make_figures.RECIPES[name].sources:
        got = make_figures.sha256(ROOT / source)
        assert inputs[f"sha256 {source}"] == got, f"{source} changed since docs/{name}.png; {FIX}"
    if "preset" in inputs:
        now = sigmapi.load_preset(inputs["preset"]).to_dict()
        assert inputs["config"] == now, f"preset {inputs['preset']} changed; {FIX}"
    if "spec" in inputs:
        assert inputs["spec_sha256"] == make_figures.sha256(ROOT / inputs["spec"]), FIX


def _shows(name: str) -> None:
    inputs = RECORD[name]["inputs"]
    _, now = make_figures.map_facts(inputs["preset"], inputs["seed"])
    assert now["shows"] == inputs["shows"], (
        f"today's code trains a map that docs/{name}.png does not show; {FIX}"
    )


def test_the_1d_figure_shows_the_map_todays_code_trains():
    _shows("fig8-1d")


@pytest.mark.slow
@pytest.mark.parametrize("name", ["fig8", "torus-fig8"])
def test_the_2d_figures_show_the_maps_todays_code_trains(name):
    _shows(name)
