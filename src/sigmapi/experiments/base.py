"""One protocol for every experiment: a typed config in, seeds given apart, a result out as data.

An :class:`Experiment`'s settings are a frozen dataclass whose fields are the command-line
options (:mod:`sigmapi.cli`); :meth:`Experiment.run` checks the config and the seeds
(:func:`check_seeds`) and calls ``execute(config, run)``, the one method an experiment writes,
which returns a :class:`~sigmapi.experiments.kit.results.Result` (:func:`write_result` writes
it as ``result.json``). Per-seed jobs run through the executor (:func:`run_all`).

Adding an experiment
--------------------
One package in ``sigmapi/experiments/`` whose ``run`` module holds its config dataclass, its
result and an experiment object passed to :func:`register`; one line in ``ENTRIES`` of
``sigmapi/experiments/__init__.py`` (name, ``"module:object"``, summary). ``sigmapi NAME`` then
has an option per config field and the common ones (seeds, output folder, JSON, executor,
quiet). The reach experiment, for instance (``sigmapi/experiments/reach/run.py``)::

    @dataclass(frozen=True)
    class ReachRun:
        episodes: int = 600
        \"\"\"Episodes of reinforcement learning per seed and state.\"\"\"

    class Reach(Experiment[ReachRun]):
        name, summary, config_type = "reach", "learn to reach from the map", ReachRun

        def execute(self, config, run):  # run: the seeds, out, executor, progress
            ...  # -> a Result

    register(Reach())
"""

from __future__ import annotations

import dataclasses
import importlib
import json
import re
import sys
import types
from collections.abc import Callable, Iterator, Mapping, MutableMapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol, TypeVar

from sigmapi import _memory, _validate
from sigmapi._outputs import write_file
from sigmapi.errors import ConfigError
from sigmapi.executor import Executor, job_error
from sigmapi.experiments.kit.results import JSON, Result
from sigmapi.experiments.kit.seeds import check_seeds
from sigmapi.progress import Progress

__all__ = [
    "KEY_VALUES",
    "REGISTRY",
    "RESULT_FILE",
    "AnyExperiment",
    "Entry",
    "Experiment",
    "Registry",
    "Result",
    "Run",
    "check_seeds",
    "read_result",
    "register",
    "run_all",
    "write_result",
]

RESULT_FILE = "result.json"
"""The file :func:`write_result` writes into an experiment's output folder."""

C = TypeVar("C")
J = TypeVar("J")
V = TypeVar("V")

KEY_VALUES: Mapping[str, object] = types.MappingProxyType({"repeat": True, "metavar": "KEY=VALUE"})
"""Field metadata of a config field of ``key=value`` strings (``field(default=(),
metadata=KEY_VALUES)``): given once per value on the command line, as values may hold commas."""


class Experiment(Protocol[C]):
    """A named experiment: a config type, default seeds, and a run that returns a :class:`Result`.

    Subclass it to inherit the defaults of the optional attributes and of
    :meth:`default_seeds`; an object with the same members works as well.
    """

    name: str
    """The command (``sigmapi NAME``) and the registry key: lower case, words joined by ``-``."""
    summary: str
    """One line for ``--help``: what the experiment does."""
    config_type: type[C]
    """The settings: a frozen dataclass, a docstring under each field; ``config_type()``
    builds the default config where every field has a default."""
    quick: C | None = None
    """A short config for a first look (None: the experiment has none)."""
    seeds: tuple[int, ...] = (0, 1, 2)
    """The default seeds."""
    quick_seeds: tuple[int, ...] | None = None
    """The default seeds of the quick config (None: :attr:`seeds`)."""
    quick_time: str | None = None
    """How long the quick run took, and on what machine, as ``--help`` says it (e.g. ``"about
    15 s on two quiet cores"``; None: not measured)."""
    extra: str | None = None
    """The extra of pyproject.toml the experiment needs (e.g. ``"robot"``; None: none), which
    its ``--help`` names with the install command (:func:`~sigmapi.errors.install_hint`)."""
    default_out: str | None = None
    """The folder the command line writes into by default (None: it writes nothing unless it
    is given one)."""
    resumes: bool = False
    """Whether a run into a folder that holds a run of the same config continues it (so that
    writing into a folder that is not empty is no mistake)."""
    writes: tuple[str, ...] = ()
    """The fixed file names the run writes into its output folder besides ``result.json``
    (checked before the work: no folder or link in their place)."""
    owns: tuple[str, ...] = ()
    """What a folder the experiment did not mark may hold, being its own (a sweep's table)."""

    def before_writing(self, config: C, *, force: bool) -> None:
        """Check, before the work, what writing the figures and files outside the output
        folder needs (a ``--render`` file, a renderer); nothing by default."""
        return None

    def default_seeds(self, config: C, *, quick: bool = False) -> tuple[int, ...]:
        """The seeds to run ``config`` with when none are given."""
        if quick and self.quick_seeds is not None:
            return self.quick_seeds
        return self.seeds

    def run(
        self,
        config: C,
        *,
        seeds: Sequence[int],
        out: Path | None = None,
        executor: Executor | None = None,
        progress: Progress | None = None,
    ) -> Result:
        """Run ``config`` (a ``config_type``) for each of ``seeds``: the config's type and the
        seeds checked, then :meth:`execute` with a :class:`Run` of ``seeds``, ``out`` (e.g. a
        sweep's table, a report's models), ``executor`` and ``progress``."""
        if not isinstance(config, self.config_type):
            raise _validate.fail("config", f"a {self.config_type.__name__}", config)
        return self.execute(config, Run(check_seeds(seeds), out, executor, progress))

    def execute(self, config: C, run: Run) -> Result:
        """What the experiment does with a checked ``config`` and ``run`` (the one method an
        experiment writes: :meth:`run` calls it)."""
        raise NotImplementedError


@dataclass(frozen=True)
class Run:
    """What :meth:`Experiment.run` hands to :meth:`Experiment.execute` besides the config."""

    seeds: tuple[int, ...]
    """Distinct non-negative ints (:func:`check_seeds`)."""
    out: Path | None = None
    """A folder for what the run writes as it goes (None: nothing)."""
    executor: Executor | None = None
    """Where the per-seed jobs run (None: one after another in this process)."""
    progress: Progress | None = None
    """Progress on stderr (None: nothing)."""


AnyExperiment = Experiment[Any]
"""An experiment of any config type (what the registry holds)."""


@dataclass(frozen=True)
class Entry:
    """An experiment not imported yet: its name, ``"module:object"`` and its one-line summary
    (what ``sigmapi --help`` shows without importing it)."""

    name: str
    target: str
    summary: str

    def load(self) -> AnyExperiment:
        """Import the module and return the object (an experiment named :attr:`name`)."""
        module, _, attr = self.target.partition(":")
        experiment = getattr(importlib.import_module(module), attr)
        if getattr(experiment, "name", None) != self.name:
            raise ConfigError(
                f"experiment entry {self.name!r} ({self.target}) loaded one named "
                f"{getattr(experiment, 'name', None)!r}; fix the entry"
            )
        return experiment

    def importing(self, experiment: object) -> bool:
        """Whether ``experiment`` is this entry's object, its module being imported now (the
        module registers what the entry names)."""
        module, _, attr = self.target.partition(":")
        found = sys.modules.get(module)
        return found is not None and getattr(found, attr, experiment) is experiment


_NAME = re.compile(r"[a-z][a-z0-9]*(-[a-z0-9]+)*")


def _check_name(name: object) -> str:
    """``name`` if it is an experiment's name: a command word (a ConfigError if not)."""
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        raise _validate.fail(
            "experiment name", "lower-case words joined by '-'", name, 'e.g. "reproduce" or "chain"'
        )
    return name


class Registry(MutableMapping[str, "AnyExperiment"]):
    """Experiments by name, each imported when first looked up (as Gymnasium does for its
    environments): ``entries`` lists them all, loaded or not, with their summaries, so that
    listing the commands imports no experiment."""

    def __init__(self) -> None:
        self.entries: dict[str, Entry] = {}
        self._loaded: dict[str, AnyExperiment] = {}

    def __getitem__(self, name: str) -> AnyExperiment:
        if name not in self._loaded:
            entry = self.entries[name]  # KeyError: no such experiment
            experiment = entry.load()  # its module calls register(), or does not
            self._loaded.setdefault(name, experiment)
        return self._loaded[name]

    def __setitem__(self, name: str, experiment: AnyExperiment) -> None:
        self._loaded[name] = experiment
        if name not in self.entries:  # registered as an object: its entry only describes it
            where = f"{type(experiment).__module__}:{type(experiment).__name__}"
            self.entries[name] = Entry(name, where, str(getattr(experiment, "summary", "")))

    def __delitem__(self, name: str) -> None:
        del self.entries[name]
        self._loaded.pop(name, None)

    def __iter__(self) -> Iterator[str]:
        return iter(self.entries)

    def __len__(self) -> int:
        return len(self.entries)

    def __contains__(self, name: object) -> bool:
        return name in self.entries

    def loaded(self, name: str) -> AnyExperiment | None:
        """The experiment ``name`` if it has been imported (else None, importing nothing)."""
        return self._loaded.get(name)

    def add(self, name: str, target: str, summary: str) -> None:
        """Register experiment ``name`` by its ``"module:object"`` without importing it."""
        _check_name(name)
        if not re.fullmatch(r"[\w.]+:\w+", target):
            raise _validate.fail(
                f"target of experiment {name!r}",
                "'module:object'",
                target,
                'e.g. "sigmapi.experiments.chain.run:CHAIN"',
            )
        if not summary:
            raise ConfigError(f"experiment {name!r} has no summary; give it one line")
        known = self.entries.get(name)
        if known is not None and known.target != target:
            raise ConfigError(
                f"experiment name {name!r} is taken by {known.target}; choose another"
            )
        self.entries[name] = Entry(name, target, summary)


REGISTRY = Registry()
"""Every registered experiment by name, imported on first look-up; the command line has a
sub-command for each (:meth:`Registry.add` registers one by its ``"module:object"``)."""


def register(experiment: Experiment[C]) -> Experiment[C]:
    """Add ``experiment`` to :data:`REGISTRY` under its ``name`` (a command word not taken by
    another experiment; its config type a frozen dataclass); returns it. A module named by a
    lazy entry (:meth:`Registry.add`) registers its experiment on import: that fills the entry."""
    name = _check_name(getattr(experiment, "name", None))
    cls = getattr(experiment, "config_type", None)
    if not (
        isinstance(cls, type) and dataclasses.is_dataclass(cls) and cls.__dataclass_params__.frozen  # type: ignore[attr-defined]
    ):
        raise _validate.fail(
            f"config_type of experiment {name!r}",
            "a frozen dataclass",
            cls,
            "decorate it with @dataclass(frozen=True)",
        )
    if not getattr(experiment, "summary", ""):
        raise ConfigError(
            f"experiment {name!r} has no summary; give it one line saying what it does"
        )
    loaded, entry = REGISTRY.loaded(name), REGISTRY.entries.get(name)
    if loaded is None and entry is not None and not entry.importing(experiment):
        raise ConfigError(f"experiment name {name!r} is taken by {entry.target}; choose another")
    if loaded is not None and loaded is not experiment:
        raise ConfigError(f"experiment name {name!r} is taken by {loaded!r}; choose another")
    REGISTRY[name] = experiment
    return experiment


def write_result(result: Result, out_dir: str | Path) -> Path:
    """Write ``result.to_dict()`` to ``out_dir/result.json`` atomically (the folder is made)."""
    folder = Path(out_dir)
    folder.mkdir(parents=True, exist_ok=True)
    text = json.dumps(result.to_dict(), indent=2)
    return write_file(folder / RESULT_FILE, (text + "\n").encode("utf-8"), what="result file")


def read_result(path: str | Path) -> JSON:
    """The dict a :func:`write_result` wrote: ``path`` is its folder or the file itself."""
    p = Path(path)
    if p.is_dir():
        p = p / RESULT_FILE
    if not p.is_file():
        raise ConfigError(f"no result at {str(p)!r}; run the experiment with that output folder")
    data = json.loads(p.read_text("utf-8"))
    if not isinstance(data, dict):
        raise ConfigError(f"{str(p)!r} holds no experiment result (not a JSON object)")
    return data


def run_all(
    fn: Callable[[J], V],
    jobs: Sequence[tuple[str, J]],
    *,
    executor: Executor | None,
    per_job: int,
    progress: Progress | None,
    desc: str,
    describe: Callable[[str, V], str] | None = None,
    verbose: Callable[[J], J] | None = None,
) -> dict[str, V]:
    """Run ``fn`` on each ``(key, arg)`` of ``jobs`` through ``executor``; the values by key.

    ``per_job`` (bytes, :func:`~sigmapi.executor.job_memory`) bounds the jobs at once. With
    progress, one line per finished job, ``describe(key, value)``; ``verbose(arg)`` gives each
    job a progress of its own where the jobs run one by one in this process, or on this machine
    into a log. A failed job raises its own error (:func:`~sigmapi.executor.job_error`)."""
    ex = executor if executor is not None else Executor(workers=1)
    if ex.engine == "local":  # a job must fit on this machine (a cluster's are its own)
        _memory.check(
            per_job,
            f"one {desc} job",
            "use smaller settings (a smaller map, grid or fewer pairs, episodes or test points)",
        )
    show = Progress.of(progress)
    plan = ex.plan(per_job, len(jobs))
    in_process = plan.workers == 1 and ex.engine == "local"
    parallel_lines = show.logs and ex.engine == "local"
    if verbose is not None and show.enabled and (in_process or parallel_lines):
        jobs = [(key, verbose(arg)) for key, arg in jobs]
    if in_process and verbose is not None and show.enabled:
        show = Progress(disable=True)  # the jobs show their own
    elif not in_process:
        show.note(f"{desc}: {len(jobs)} jobs, {plan.reason}")
    done, bar = show.jobs(len(jobs), desc)
    values: dict[str, V] = {}
    with bar:
        for o in ex.run(fn, jobs, plan.workers):
            if not o.ok:
                raise job_error(f"{desc} job {o.key}", o.error or "")
            values[o.key] = o.value
            done(True, describe(o.key, o.value) if describe else f"{o.key} ({o.seconds:.0f} s)")
    return {key: values[key] for key, _ in jobs}
