"""Training checkpoints that survive a kill (``sigmapi train`` writes them and resumes from them).

Checkpoints of a run writing ``OUT`` live in the folder ``OUT.ckpt/`` as ordinary model files
``step-000000012000.npz`` (weights, backend state, iteration count, seed entropy, config, and
checksums of the arrays and of the header itself), each written atomically (temp file, fsync,
rename, fsync of the folder). Resuming takes the newest checkpoint that loads cleanly and was
made with the same config; a damaged one is reported and skipped. Because the training data of
every iteration is a pure function of the seed and the iteration number, the resumed run ends
with exactly the weights of an uninterrupted run.

Safety: a checkpoint folder that is a symbolic link is refused (its files would be pruned
wherever it points); temporary files of checkpoint writes killed earlier (``.step-*.tmp``,
idle for a minute) are removed by the next write; only names of this pattern are ever
deleted. When the run has finished, :func:`remove_checkpoints` deletes them (the command line
does, unless asked to keep them).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from sigmapi.errors import ModelFileError
from sigmapi.io import stale_temps

if TYPE_CHECKING:
    from sigmapi.config import SOMConfig
    from sigmapi.model.som import SigmaPiSOM

__all__ = [
    "Resumed",
    "checkpoint_dir",
    "find_resumable",
    "list_checkpoints",
    "remove_checkpoints",
    "write_checkpoint",
]

_NAME = re.compile(r"^step-(\d{12})\.npz$")
_TEMP = r"step-\d{12}\.npz"


def checkpoint_dir(out: str | Path) -> Path:
    """The checkpoint folder of a run that writes ``out``."""
    p = Path(out)
    return p.with_name(p.name + ".ckpt")


def _check_folder(folder: Path) -> None:
    if folder.is_symlink():
        raise ModelFileError(
            f"checkpoint folder {str(folder)!r} is a symbolic link (to "
            f"{os.readlink(folder)!r}); refused, as its files would be written and pruned "
            "there: remove the link or write the run to another path"
        )
    if folder.exists() and not folder.is_dir():
        raise ModelFileError(f"checkpoint folder {str(folder)!r} exists and is not a folder")


def list_checkpoints(folder: Path) -> list[tuple[int, Path]]:
    """(iteration, path) of the checkpoint files in ``folder``, newest first."""
    _check_folder(folder)
    if not folder.is_dir():
        return []
    found = []
    for p in folder.iterdir():
        m = _NAME.match(p.name)
        if m and p.is_file() and not p.is_symlink():
            found.append((int(m.group(1)), p))
    return sorted(found, reverse=True)


def write_checkpoint(model: SigmaPiSOM, folder: Path, keep: int = 3) -> Path:
    """Write ``model`` as the newest checkpoint in ``folder``; keep the ``keep`` newest.

    Also removes temporary files that killed checkpoint writes left in ``folder``.
    """
    _check_folder(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for old in stale_temps(folder, _TEMP):
        old.unlink(missing_ok=True)
    path = model.save(folder / f"step-{model.t_:012d}.npz")
    for _, old in list_checkpoints(folder)[keep:]:
        old.unlink(missing_ok=True)
    return path


def remove_checkpoints(folder: Path) -> int:
    """Delete the checkpoints and checkpoint temp files in ``folder`` (the run has finished:
    temp files are debris of killed writes, however recent), and the folder if it is then
    empty; returns how many checkpoints were deleted. Other files are left alone."""
    found = list_checkpoints(folder)
    for _, p in found:
        p.unlink(missing_ok=True)
    if folder.is_dir():
        for old in stale_temps(folder, _TEMP, idle_s=-1.0):
            old.unlink(missing_ok=True)
        try:
            folder.rmdir()
        except OSError:  # not empty: someone else's files
            pass
    return len(found)


@dataclass
class Resumed:
    """The model to continue (None: start afresh) and the checkpoints that were skipped."""

    model: SigmaPiSOM | None
    path: Path | None
    skipped: list[str] = field(default_factory=list)


def find_resumable(folder: Path, config: SOMConfig) -> Resumed:
    """The newest checkpoint in ``folder`` that loads cleanly and matches ``config``."""
    from sigmapi.model.som import load_model

    skipped: list[str] = []
    for _, path in list_checkpoints(folder):
        try:
            model = load_model(path)
        except ModelFileError as exc:
            skipped.append(f"{path.name}: {exc}")
            continue
        if model.config != config:
            skipped.append(f"{path.name}: made with another config (not this command line)")
            continue
        return Resumed(model, path, skipped)
    return Resumed(None, None, skipped)
