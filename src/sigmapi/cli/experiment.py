"""The sub-command of each registered experiment, generated from the experiment and its config.

``sigmapi NAME`` gets an option per field of ``experiment.config_type``
(:func:`~sigmapi.cli._common.add_dataclass_flags`) and the options every experiment shares:

- ``--seeds S [S ...]``: the seeds themselves (not a count), distinct ints >= 0; default the
  experiment's (:meth:`~sigmapi.experiments.Experiment.default_seeds`);
- ``--out DIR``: the folder for ``result.json`` (``to_dict()``) and the figures (default the
  experiment's, or nothing written). It holds one experiment, marked by the file
  ``.sigmapi-experiment`` (:func:`sigmapi._outputs.claim_folder`): a folder marked for
  another experiment is refused, ``--force`` or not; a folder that is not empty needs
  ``--force``, unless it is marked for this experiment and the experiment resumes a run there
  (a sweep: it owns its table, figure and ``result.json``, and refuses a table it did not
  write, ``--force`` or not); the folder is locked while the command runs
  (:mod:`sigmapi._lock`: a second command on it stops at once) and checked to take files
  before any work, as are the files the experiment writes elsewhere and what its figures
  need (its ``before_writing(config, force=...)``: ``robot --render``, the renderer) and
  its fixed file names (its ``writes``);
- ``--json``: print ``to_dict()`` as one JSON object on stdout (else the table);
- ``--quick``: start from the experiment's quick config and seeds (where it has one);
- ``--workers``, ``--engine``, ``--address``, ``--memory-budget``: the executor;
- ``--quiet``: no progress on stderr.

A config field keeps its name as its option (``train_pairs``: ``--train-pairs``); the fields
that have a second, shorter spelling on every command are in :data:`SPELLINGS`.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import os
import sys
import tempfile
from functools import partial
from pathlib import Path
from typing import Any

from sigmapi._lock import LOCK_NAME, output_lock
from sigmapi._outputs import MARKER, claim_folder, marked_as
from sigmapi.cli._common import (
    Parser,
    add_dataclass_flags,
    add_workers_flag,
    dataclass_values,
    declare_path,
    plain,
)
from sigmapi.errors import ConfigError, UsageError, install_hint
from sigmapi.executor import ENGINES, Executor
from sigmapi.experiments.base import (
    REGISTRY,
    RESULT_FILE,
    AnyExperiment,
    Experiment,
    Result,
    check_seeds,
    write_result,
)
from sigmapi.experiments.kit.parts import parts_of
from sigmapi.progress import Progress

__all__ = ["SPELLINGS", "add_experiment", "add_experiment_options", "run_experiment"]

SPELLINGS: dict[str, str] = {
    "overrides": "--set",  # key=value changes to a preset, as `sigmapi train --set`
    "save_models": "--models",
    "model_path": "--model",
}
"""A second option per config field name, the same on every command."""


def _gib(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = 0.0
    if not 0 < value < 2**40:  # NaN and inf too
        raise argparse.ArgumentTypeError(
            f"must be a positive, finite number of GiB, got {text[:40]!r}; e.g. 8"
        )
    return value


def _seeds_default(experiment: AnyExperiment) -> str:
    """How ``--help`` states the default seeds."""
    if getattr(type(experiment), "default_seeds", None) is Experiment.default_seeds:
        seeds, quick = experiment.seeds, experiment.quick_seeds or experiment.seeds
    else:  # they may follow from the config: ask the default config, where there is one
        try:
            config = experiment.config_type()
        except TypeError:  # a field without a default
            return "the config's"
        seeds = experiment.default_seeds(config)
        if experiment.quick is not None:
            quick = experiment.default_seeds(experiment.quick, quick=True)
    text = " ".join(map(str, seeds))
    if experiment.quick is not None:
        text += "; --quick: " + " ".join(map(str, quick))
    return text


def add_experiment(sub: Any, name: str, summary: str) -> Parser:
    """Add the sub-command ``name`` to the sub-parsers ``sub`` (made with
    ``parser_class=LazyParser``): its options are added, and the experiment
    (``REGISTRY[name]``) imported, only when the command is used; returns its parser."""
    return sub.add_parser(
        name, help=plain(summary), fill=lambda p: add_experiment_options(p, REGISTRY[name])
    )


def add_experiment_options(p: Parser, experiment: AnyExperiment) -> None:
    """Give ``p`` the options of ``experiment`` (its config's fields and the common ones)."""
    p.description = plain(type(experiment).__doc__ or experiment.summary)
    if experiment.extra:
        p.description += f" Needs the {experiment.extra} extra: {install_hint(experiment.extra)}."
    common = p.add_argument_group("common to every experiment")
    common.add_argument(
        "--seeds",
        type=int,
        nargs="+",
        metavar="S",
        help=f"the seeds (not a count), distinct ints >= 0 (default: {_seeds_default(experiment)})",
    )
    out = experiment.default_out
    common.add_argument(
        "--out",
        metavar="DIR",
        default=out,
        help="folder for result.json and the figures (default: "
        + (f"./{out})" if out else "none: nothing is written)"),
    )
    declare_path(p, "out", "--out", "folder")
    common.add_argument(
        "--force", action="store_true", help="write into an --out folder that is not empty"
    )
    common.add_argument(
        "--json", action="store_true", help="print the result as one JSON object on stdout"
    )
    if experiment.quick is not None:
        took = experiment.quick_time
        common.add_argument(
            "--quick",
            action="store_true",
            help="a first look: shorter settings, fewer seeds" + (f" ({took})" if took else ""),
        )
    add_workers_flag(common, "jobs")
    common.add_argument(
        "--engine",
        choices=ENGINES,
        default="local",
        help="local: a process pool on this machine (default); dask: a Dask "
        f"cluster (--address, or a local one; {install_hint('sweep')})",
    )
    common.add_argument("--address", help="Dask scheduler address, e.g. tcp://10.0.0.5:8786")
    common.add_argument(
        "--memory-budget",
        type=_gib,
        default=None,
        metavar="GIB",
        help="memory the parallel jobs may use together (default: half of the available memory)",
    )
    common.add_argument("--quiet", action="store_true", help="no progress on stderr")
    taken = {a.dest for a in p._actions}
    for group, cls in _parts(experiment).items():
        names = {f.name for f in dataclasses.fields(cls)}
        where = p if group is None else p.add_argument_group(f"{group} settings")
        add_dataclass_flags(where, cls, aliases=SPELLINGS, skip=names & taken)
    p.set_defaults(func=partial(run_experiment, experiment))


def _missing_folders(out: Path) -> list[Path]:
    """The folders ``out`` and its parents that do not exist yet, innermost first (the ones
    :func:`_make_folder` creates)."""
    made = []
    for folder in (out, *out.parents):
        if folder.exists() or str(folder) in ("", "."):
            break
        made.append(folder)
    return made


def _make_folder(path: str) -> Path:
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out {str(out)!r} is a file; give a folder")
    out.mkdir(parents=True, exist_ok=True)
    return out


def _parts(experiment: AnyExperiment) -> dict[str | None, type]:
    """The dataclasses whose fields are the command's options: the config's own (key None),
    or, for a config made of parts (:class:`~sigmapi.experiments.kit.parts.Parts`: each field
    a part's dataclass, and ``replace(**fields)`` finding the part of each field), every
    part's."""
    parts: dict[str | None, type] = dict(parts_of(experiment.config_type).items())
    return parts or {None: experiment.config_type}


def _check_folder(out: Path, force: bool, experiment: AnyExperiment) -> None:
    """Before any work: the folder takes files, and is this experiment's
    (:func:`~sigmapi._outputs.claim_folder`: its marker, or empty, or ``--force``); a run
    that does not resume needs ``--force`` to write over a run of its own there."""
    for name in (RESULT_FILE, *experiment.writes):
        if (out / name).is_symlink() or ((out / name).exists() and not (out / name).is_file()):
            raise UsageError(
                f"{str(out / name)!r} is a folder or a link; the command writes a "
                "file there: move it away or give another --out"
            )
    try:  # find out now, not after a long run, that the folder takes no files
        fd, probe = tempfile.mkstemp(prefix=".sigmapi.", suffix=".tmp", dir=out)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise UsageError(
            f"cannot write into --out folder {str(out)!r}: {exc.strerror or exc}; choose "
            "another --out"
        ) from None
    own = marked_as(out) == experiment.name
    if (
        own
        and not (force or experiment.resumes)
        and any(p.name not in (LOCK_NAME, MARKER) for p in out.iterdir())
    ):
        raise UsageError(
            f"--out folder {str(out)!r} is not empty; pass --force to write into it (it holds "
            f"a {experiment.name} run), or give another --out"
        )
    claim_folder(out, experiment.name, force=force, owns=experiment.owns)


def _config(experiment: AnyExperiment, values: dict[str, object], quick: bool) -> object:
    """The config of the flags (from the quick one with ``--quick``); an error that only the
    ``--set`` overrides cause names the flag, as ``sigmapi train`` does."""
    start = experiment.quick if quick and experiment.quick is not None else None

    def build(given: dict[str, object]) -> object:
        if None not in _parts(experiment):  # a config of parts: each field finds its part
            base = start if start is not None else experiment.config_type()
            return base.replace(**given) if given else base
        if start is not None:
            return dataclasses.replace(start, **given)
        return experiment.config_type(**given)

    try:
        return build(values)
    except ConfigError as exc:
        if "overrides" not in values:
            raise
        build({k: v for k, v in values.items() if k != "overrides"})  # fails alike: not --set's
        raise ConfigError(f"--set: {exc}") from None


def run_experiment(experiment: AnyExperiment, args: argparse.Namespace) -> int:
    """Build the config from the flags, run the experiment, write ``result.json`` and the
    figures into ``--out``, print the table (or the JSON)."""
    quick = bool(getattr(args, "quick", False))
    values = {
        k: v for cls in _parts(experiment).values() for k, v in dataclass_values(args, cls).items()
    }
    config = _config(experiment, values, quick)
    if args.seeds is not None:
        seeds = check_seeds(args.seeds)
    else:
        seeds = experiment.default_seeds(config, quick=quick)
    budget = None if args.memory_budget is None else int(args.memory_budget * 2**30)
    executor = Executor(args.engine, args.workers, args.address, budget)
    if args.out is None:
        result = _run(experiment, config, seeds, None, executor, args.quiet)
    else:
        made = _missing_folders(Path(args.out))
        out = _make_folder(args.out)
        was_marked = marked_as(out) is not None
        try:
            with output_lock(out, f"--out folder {str(out)!r}"):
                _check_folder(out, args.force, experiment)
                # what its figures and files outside --out need
                experiment.before_writing(config, force=args.force)
                before = _stamps(out)
                result = _run(experiment, config, seeds, out, executor, args.quiet)
                files = _written(out, before, [*result.figure(out), write_result(result, out)])
        except BaseException:  # a run that fails (a missing extra) leaves no empty folder
            if not was_marked and [p.name for p in out.iterdir()] == [MARKER]:
                (out / MARKER).unlink()  # the marker this run wrote, alone: nothing to resume
            for folder in made:
                with contextlib.suppress(OSError):
                    folder.rmdir()  # only an empty one
            raise
    print(json.dumps(result.to_dict()) if args.json else result.table())
    if args.out is not None:
        print(f"sigmapi {experiment.name}: wrote {', '.join(map(str, files))}", file=sys.stderr)
    return 0


def _stamps(out: Path) -> dict[Path, tuple[int, int]]:
    """Each file under ``out`` (the run's own lock and marker aside): its modification time
    and size, to tell after the run which files it wrote."""
    found = {}
    for path in sorted(out.rglob("*")):
        if path.name in (LOCK_NAME, MARKER) or path.is_symlink() or not path.is_file():
            continue
        st = path.stat()
        found[path] = (st.st_mtime_ns, st.st_size)
    return found


def _written(out: Path, before: dict[Path, tuple[int, int]], listed: list[Path]) -> list[Path]:
    """Every file the run wrote: those its result lists (its figures, ``result.json``, a file
    outside ``--out``) and every other file under ``out`` that is new or changed since
    ``before`` (a report, its data, captions, saved models), each once."""
    files = {Path(f): None for f in listed}
    for path, stamp in _stamps(out).items():
        if before.get(path) != stamp:
            files.setdefault(path)
    return list(files)


def _run(
    experiment: AnyExperiment,
    config: object,
    seeds: tuple[int, ...],
    out: Path | None,
    executor: Executor,
    quiet: bool,
) -> Result:
    executor.check()  # a scheduler that does not answer: before any work
    progress = None if quiet else Progress()
    return experiment.run(config, seeds=seeds, out=out, executor=executor, progress=progress)
