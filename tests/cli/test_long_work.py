"""Long work says how long, in a log as on a terminal; every command that needs an extra says
so, and how long its quick run takes, in its help; a mistyped option gets the closest one."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from sigmapi import progress
from sigmapi.cli import main
from sigmapi.errors import install_hint
from sigmapi.experiments import REGISTRY

STATUS = re.compile(
    r"^(?P<desc>.+): (?P<n>[\d,]+) of (?P<total>[\d,]+) (?P<unit>\w+) after [\dminhs ]+, "
    r"(?P<left>[\d,]+) left, (about (?P<eta>[\dminhs ]+) more \([\d.,e+-]+ \w+/s\)|"
    r"no estimate before the first is done)(; .+)?$"
)
"""A heartbeat's status line (sigmapi.progress.Lines.status): done, total, left, estimate."""


def _status(text: str) -> list[re.Match[str]]:
    return [m for m in map(STATUS.match, text.splitlines()) if m]


def test_train_into_a_log_says_what_is_done_left_and_how_long_it_takes(tmp_path):
    log = tmp_path / "log"
    env = {**os.environ, "SIGMAPI_HEARTBEAT_S": "0.02"}  # the 20 s of a real run, shortened
    with log.open("w") as err:  # stderr a file: `sigmapi train ... 2> log`
        r = subprocess.run(
            [sys.executable, "-m", "sigmapi.cli", "train", "--preset", "tiny-1d", "--set",
             "iterations=6000", "--backend", "reference", "--out", str(tmp_path / "m.npz")],
            stdout=subprocess.DEVNULL, stderr=err, env=env, timeout=120,
        )  # fmt: skip
    text = log.read_text()
    assert r.returncode == 0, text
    found = [m for m in _status(text) if m["eta"]]
    assert found, text
    for m in found:
        n, total, left = (int(m[k].replace(",", "")) for k in ("n", "total", "left"))
        assert m["desc"] == "train tiny-1d" and m["unit"] == "it"
        assert total == 6000 and n + left == total and 0 < n <= total
    assert "\r" not in text  # plain lines, no bar
    assert text.splitlines()[-2].startswith("train tiny-1d: 6,000 of 6,000 it in ")


def test_an_experiment_into_a_log_shows_its_jobs_work_with_an_estimate(
    tmp_path, monkeypatch, capsys
):
    monkeypatch.setattr(progress.HEART, "period", 0.05)  # the 20 s of a real run, shortened
    import time

    from sigmapi.experiments.chain import run as chain_run

    counted_by_kit = chain_run.iterations_counted

    def slowed(tick, name, iterations):  # a quiet machine trains this map in 0.1 s: each
        inner = counted_by_kit(tick, name, iterations)  # count waits 0.02 s, so that the
        if inner is None:  # heartbeat (every 0.05 s) speaks during the training on any machine
            return None
        return lambda model: (time.sleep(0.02), inner(model))[1]

    monkeypatch.setattr(chain_run, "iterations_counted", slowed)
    log = tmp_path / "log"
    with log.open("w") as err:  # stderr a file: `sigmapi chain ... 2> log`
        monkeypatch.setattr(sys, "stderr", err)
        argv = ["chain", "--quick", "--set", "iterations=10000", "--train-pairs", "300"]
        assert main([*argv, "--n-test", "100"]) == 0
    text = log.read_text()
    found = [m for m in _status(text) if m["eta"]]
    assert found, text
    for m in found:
        n, total, left = (int(m[k].replace(",", "")) for k in ("n", "total", "left"))
        assert (m["desc"], m["unit"], total, n + left) == ("chain seed 0", "it", 30_000, total)
    assert text.splitlines()[-1].startswith("chain seed 0: 30,000 of 30,000 it in ")


def test_the_heartbeat_thread_writes_while_nothing_is_counted(monkeypatch, capsys):
    monkeypatch.setattr(progress.HEART, "period", 0.05)
    import time

    step, bar = progress.counter(3, "slow", "step")
    with bar:
        step(0, "the first step")
        time.sleep(0.5)  # a step that takes long: the heartbeat speaks
    found = _status(capsys.readouterr().err)
    assert len(found) >= 3 and all(m["desc"] == "slow" for m in found)
    assert found[0].group(0).endswith("no estimate before the first is done; the first step")


def _help(name: str, capsys) -> str:
    with pytest.raises(SystemExit) as exc:
        main([name, "--help"])
    assert exc.value.code == 0
    return " ".join(capsys.readouterr().out.split())


def _needs_an_extra(name: str) -> str | None:
    """The extra an experiment's code reaches for, read from its package's source: MuJoCo or
    the iCub's models (robot), the baselines' packages (baselines)."""
    module = REGISTRY.entries[name].target.partition(":")[0]
    folder = Path(sys.modules["sigmapi"].__file__).parent / "experiments" / module.split(".")[2]
    text = "".join(p.read_text("utf-8") for p in sorted(folder.glob("*.py")))
    if re.search(r"mujoco_module|icub_models|sigmapi\.envs\.(robot|icub)", text):
        return "robot"
    if re.search(r"sigmapi\.baselines|check_installed|minisom|sklearn", text):
        return "baselines"
    return None


@pytest.mark.parametrize("name", sorted(REGISTRY))
def test_help_names_the_extra_a_command_needs_and_the_quick_runs_time(name, capsys):
    text = _help(name, capsys)
    need = _needs_an_extra(name)
    assert REGISTRY[name].extra == need
    if need is not None:
        assert f"Needs the {need} extra: {install_hint(need)}." in text
    else:
        assert "Needs the" not in text
    if REGISTRY[name].quick is not None:
        assert re.search(r"--quick a first look: [^()]+ \(about [\d.]+(-[\d.]+)? (s|min) ", text), (
            text
        )
    assert install_hint("sweep") in text  # --engine dask


def test_export_help_names_the_onnx_extra(capsys):
    assert f"Needs the onnx extra: {install_hint('onnx')}." in _help("export", capsys)


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["neurons", "--quik"], "sigmapi neurons: error: unrecognized arguments: --quik; "
         "did you mean --quick?"),
        (["icub", "--quick", "--seds", "1"], "sigmapi icub: error: unrecognized arguments: "
         "--seds 1; did you mean --seeds?"),
        (["nuerons", "--quick"], "sigmapi: error: argument command: invalid choice: 'nuerons' "),
        (["chain", "--quick", "stray"], "sigmapi chain: error: unrecognized arguments: stray"),
    ],
)  # fmt: skip
def test_a_typo_is_the_commands_and_gets_the_closest_option(argv, said, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.startswith(said) and len(err.splitlines()) == 1
    if argv[0] == "nuerons":
        assert err.rstrip().endswith("; did you mean neurons?")
    if argv[-1] == "stray":
        assert "did you mean" not in err


def _dask_check() -> None:
    from sigmapi.executor import Executor

    Executor("dask").check()


@pytest.mark.parametrize(
    ("module", "extra", "call"),
    [
        ("mujoco", "robot", "sigmapi.envs.robot.scene:mujoco_module"),
        ("icub_models", "robot", "sigmapi.envs.icub.model:icub_models_module"),
        ("onnx", "onnx", "sigmapi.export:_onnx"),
        ("distributed", "sweep", None),
    ],
)
def test_a_missing_extra_is_said_in_one_form_everywhere(module, extra, call, monkeypatch):
    import importlib

    from sigmapi.errors import SigmapiError

    monkeypatch.setitem(sys.modules, module, None)  # `import module` fails as if not installed
    fn = _dask_check
    if call is not None:
        where, _, name = call.partition(":")
        fn = getattr(importlib.import_module(where), name)
    with pytest.raises(SigmapiError) as exc:
        fn()
    text = str(exc.value)
    assert "(not installed here" in text and text.endswith(f"); {install_hint(extra)}"), text
    assert "clone: pip install '.[" in install_hint(extra)  # as the README installs


def test_the_readme_installs_every_extra_a_command_asks_for():
    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text("utf-8")
    asked = {e.extra for e in REGISTRY.values() if e.extra} | {"onnx", "sweep"}  # export, dask
    for extra in sorted(asked):
        assert f"'.[{extra}]'" in readme, extra  # the clone's form of install_hint(extra)
