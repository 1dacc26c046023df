"""Results read back from their JSON form: every experiment result the docs render has a
``from_dict``, ``to_dict -> from_dict -> to_dict`` is the identity, and the results files kept
in ``benchmarks/results/`` read back with the values they hold (a key a newer version added
may join them, at its default)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from sigmapi.errors import ConfigError, DataError
from sigmapi.experiments.chain.run import ChainResult
from sigmapi.experiments.compare.run import CompareResult
from sigmapi.experiments.icub.result import ICubResult
from sigmapi.experiments.neurons.result import NeuronsResult
from sigmapi.experiments.reach.result import ReachResult
from sigmapi.experiments.reproduce.results import ReproduceResult
from sigmapi.experiments.reward.result import RewardResult
from sigmapi.experiments.robot.result import RobotResult
from sigmapi.experiments.stream.run import StreamResult
from sigmapi.experiments.sweep.run import SweepResult

RESULTS = Path(__file__).resolve().parents[2] / "benchmarks" / "results"

KEPT: list[tuple[str, Any, str]] = [
    ("chain", ChainResult, ""),
    ("compare", CompareResult, ""),
    ("icub", ICubResult, ""),
    ("icub-check", ICubResult, ""),
    ("icub-box", ICubResult, ""),  # reads back as an ICubBoxResult (its "space" is "box")
    ("icub-box-balls", ICubResult, ""),
    ("neurons", NeuronsResult, ""),
    ("reach", ReachResult, ""),
    ("reproduce", ReproduceResult, "metrics"),
    ("reward", RewardResult, "result"),
    ("reward-eps0.5", RewardResult, "result"),
    ("robot-docking", RobotResult, "result"),
    ("robot-docking-quick", RobotResult, "result"),
    ("robot-docking-tuning", RobotResult, "result"),
    ("stream", StreamResult, ""),
    ("paper-1d-procedures", SweepResult, ""),
    ("paper-2d-procedures", SweepResult, ""),
]
"""Each kept result file, the class that reads it, and the key it sits under ("" at the top)."""

KEEPER_KEYS = {"command", "machine", "wall_s", "cpu_s", "load_avg_1min", "commit", "load_note",
               "sigmapi_command", "measured"}  # fmt: skip
"""What the script that kept a result added beside it (its command, the machine, the time)."""


def _json(data: Any) -> Any:
    return json.loads(json.dumps(data))


def _within(kept: Any, read: Any, where: str = "") -> None:
    """Every value of ``kept`` is in ``read`` at the same place (``read`` may hold more)."""
    if isinstance(kept, dict):
        assert isinstance(read, dict), where
        for k, v in kept.items():
            assert k in read, f"{where}.{k}"
            _within(v, read[k], f"{where}.{k}")
    else:
        assert read == kept, where


@pytest.mark.parametrize(("name", "cls", "key"), KEPT, ids=[k[0] for k in KEPT])
def test_a_kept_result_reads_back_with_its_values(name, cls, key):
    data = json.loads((RESULTS / f"{name}.json").read_text("utf-8"))
    inner = data[key] if key else {k: v for k, v in data.items() if k not in KEEPER_KEYS}
    out = _json(cls.from_dict(inner).to_dict())
    _within(inner, out)
    assert _json(cls.from_dict(out).to_dict()) == out  # and again: the identity


@pytest.mark.parametrize(("name", "cls", "key"), KEPT, ids=[k[0] for k in KEPT])
def test_a_kept_result_read_back_draws_its_figures_or_says_why_not(name, cls, key, tmp_path):
    data = json.loads((RESULTS / f"{name}.json").read_text("utf-8"))
    result = cls.from_dict(data[key] if key else data)
    if name.startswith("icub"):  # its figures show frames, balls and reaches the file lacks
        with pytest.raises(DataError, match="no records per seed"):
            result.figure(tmp_path)
        return
    paths = result.figure(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [p.name for p in paths] + [p.with_suffix(".txt").name for p in paths]
    )
    for p in paths:
        assert p.stat().st_size > 1000 and p.with_suffix(".txt").read_text("utf-8").strip()


def test_a_result_read_back_without_a_key_names_it():
    data = json.loads((RESULTS / "reach.json").read_text("utf-8"))
    del data["curves"]
    with pytest.raises(KeyError, match="curves"):
        ReachResult.from_dict(data)
    with pytest.raises(TypeError, match="JSON object"):
        ReachResult.from_dict([1, 2])


def test_a_config_read_back_with_a_field_it_lacks_names_the_field():
    data = json.loads((RESULTS / "reach.json").read_text("utf-8"))
    data["config"]["run"]["episodez"] = 5
    with pytest.raises(ConfigError, match="'episodez' in part 'run'"):
        ReachResult.from_dict(data)
    data["config"]["run"] = [1]
    with pytest.raises(ConfigError, match="part 'run' must be a JSON object"):
        ReachResult.from_dict(data)


@pytest.mark.parametrize(("drop", "table"), [("success", "reach"), ("methods", "compare")])
def test_the_docs_read_a_result_through_its_class_and_name_the_file_and_key(
    tmp_path, monkeypatch, drop, table
):
    """The docs' results tables read a result file by its ``from_dict``: a file lacking a
    key fails the build with the file and the key named."""
    pytest.importorskip("sphinx")
    monkeypatch.syspath_prepend(str(RESULTS.parents[1] / "docs" / "_ext"))
    import sigmapi_results
    from sphinx.errors import ExtensionError

    data = json.loads((RESULTS / f"{table}.json").read_text("utf-8"))
    monkeypatch.setattr(sigmapi_results, "RESULTS", tmp_path)
    (tmp_path / f"{table}.json").write_text(json.dumps(data))
    sigmapi_results._load_cached.cache_clear()
    assert sigmapi_results.TABLES[table]().rows
    del data[drop]
    (tmp_path / f"{table}.json").write_text(json.dumps(data))
    with pytest.raises(ExtensionError, match=rf"{table}\.json: no key '{drop}'"):
        sigmapi_results.TABLES[table]()
