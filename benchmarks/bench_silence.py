"""How long a command leaves its log silent: the longest gap between two lines on stderr.

Runs each command with stderr a pipe (as ``sigmapi ... 2> log``: no terminal, so plain progress
lines), timestamps every line as it arrives and records the wall time, the longest gap between
two lines (from the start to the first line and from the last line to the exit included), the
number of lines and of status lines (what is done, what is left, the time left:
:meth:`sigmapi.progress.Lines.status`), and the load average before and after::

    MUJOCO_GL=egl python benchmarks/bench_silence.py "neurons --quick" "icub --quick"

Writes ``benchmarks/results/silence.json`` (``--out``); each command runs once, into a fresh
temporary ``--out`` folder, in the order given. The promise it checks: no command is silent
for more than 30 s (a status line at least every 20 s while a bar is open).
"""

from __future__ import annotations

import argparse
import itertools
import os
import re
import shlex
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from _common import commit, machine, write_result

ROOT = Path(__file__).resolve().parents[1]
STATUS = re.compile(r": [\d,]+ of [\d,]+ .* after .*, [\d,]+ left, ")


def measure(command: str, out: Path) -> dict[str, Any]:
    """Run ``sigmapi COMMAND --out OUT`` and time its stderr lines."""
    argv = [sys.executable, "-m", "sigmapi.cli", *shlex.split(command), "--out", str(out)]
    load_before = os.getloadavg()
    start = time.monotonic()
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    stamps: list[tuple[float, str]] = []

    def read() -> None:
        assert proc.stderr is not None
        for line in proc.stderr:
            stamps.append((time.monotonic() - start, line.rstrip("\n")))

    reader = threading.Thread(target=read)
    reader.start()
    code = proc.wait()
    wall = time.monotonic() - start
    reader.join()
    times = [0.0, *(t for t, _ in stamps), wall]
    gaps = [b - a for a, b in itertools.pairwise(times)]
    worst = max(range(len(gaps)), key=gaps.__getitem__)
    return {
        "command": f"sigmapi {command} --out DIR",
        "exit_code": code,
        "wall_s": round(wall, 1),
        "longest_gap_s": round(gaps[worst], 1),
        "longest_gap_ends_with": stamps[worst][1] if worst < len(stamps) else "(the exit)",
        "lines": len(stamps),
        "status_lines": sum(bool(STATUS.search(line)) for _, line in stamps),
        "load_average_1min": [round(load_before[0], 2), round(os.getloadavg()[0], 2)],
    }


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("commands", nargs="+", help='sigmapi commands, e.g. "neurons --quick"')
    p.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "silence.json")
    args = p.parse_args()
    runs = []
    for command in args.commands:
        with tempfile.TemporaryDirectory() as tmp:
            run = measure(command, Path(tmp) / "out")
        print(f"sigmapi {command}: {run['wall_s']} s, longest gap {run['longest_gap_s']} s")
        runs.append(run)
    argv = " ".join(shlex.quote(c) for c in args.commands)
    write_result(
        args.out,
        {
            "command": f"python benchmarks/bench_silence.py {argv}",
            "commit": commit(ROOT / "src"),
            "machine": machine(note="2 cores shared with other jobs: see load_average_1min"),
            "runs": runs,
        },
    )


if __name__ == "__main__":
    main()
