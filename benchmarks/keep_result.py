"""Run an experiment command and keep its result.json in benchmarks/results/, with how it ran.

The documentation's results pages render their tables from ``benchmarks/results/*.json``. This
runs the command (which must write ``OUT/result.json``; ``OUT`` in the command is replaced by a
temporary folder) and writes ``benchmarks/results/NAME.json``: the result, and on top of it the
command, wall and CPU seconds (the command and its children) and the 1-minute load average
before and after (the machine may be shared):

    python benchmarks/keep_result.py chain -- sigmapi chain --seeds 100 101 --json --out OUT
    python benchmarks/keep_result.py paper-1d-procedures -- \\
        sigmapi sweep benchmarks/specs/paper-1d-procedures.toml --out OUT
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").partition("\n")[0])
    parser.add_argument("name", help="the file to write: benchmarks/results/NAME.json")
    parser.add_argument("command", nargs=argparse.REMAINDER, help="-- then the command")
    args = parser.parse_args()
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if "OUT" not in command:
        parser.error("the command must write its result to OUT (e.g. --out OUT)")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        argv = [str(out) if a == "OUT" else a for a in command]
        load0, t0 = os.getloadavg()[0], time.perf_counter()
        subprocess.run(argv, check=True, stdout=subprocess.DEVNULL)
        wall, load1 = time.perf_counter() - t0, os.getloadavg()[0]
        usage = resource.getrusage(resource.RUSAGE_CHILDREN)
        result = json.loads((out / "result.json").read_text("utf-8"))
    record = {
        "command": " ".join(command),
        "machine": {"cpus": os.cpu_count(), "platform": platform.platform(),
                    "python": platform.python_version()},
        "wall_s": round(wall, 1),
        "cpu_s": round(usage.ru_utime + usage.ru_stime, 1),
        "load_avg_1min": [round(load0, 2), round(load1, 2)],
        **result,
    }  # fmt: skip
    target = RESULTS / f"{args.name}.json"
    tmp_target = target.with_suffix(".json.tmp")
    tmp_target.write_text(json.dumps(record, indent=2) + "\n", "utf-8")
    os.replace(tmp_target, target)
    print(f"{target}: {wall:.0f} s wall, {record['cpu_s']:.0f} s CPU", file=sys.stderr)


if __name__ == "__main__":
    main()
