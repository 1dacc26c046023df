"""Learning from a stream against explicit pairs, measured as a user runs it: ``sigmapi stream``
on groups of seeds, one command per group (each writes its ``result.json``), then the groups
combined into one JSON with the commands, wall and CPU seconds and the load average.

    python benchmarks/bench_stream.py --groups 800-804 805-809 --traces 0,0.5 \\
        --work /tmp/stream --out benchmarks/results/stream.json

A group whose folder already holds a ``result.json`` is not run again (``--force`` runs it
anyway), so an interrupted measurement continues with the next group; its timings are kept from
the ``--out`` file where that holds them. ``--figure FILE.png`` draws the combined figure.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path

from sigmapi.experiments.base import read_result
from sigmapi.experiments.stream.run import StreamResult


def _seeds(text: str) -> list[int]:
    lo, _, hi = text.partition("-")
    return list(range(int(lo), int(hi or lo) + 1))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--groups",
        nargs="+",
        default=["800-804", "805-809"],
        help="seed ranges, one sigmapi stream command each (e.g. 800-804)",
    )
    p.add_argument("--traces", default="0,0.5", help="trace constants (comma-separated)")
    p.add_argument("--dwells", default="1,2,4,8,16", help="dwell times (comma-separated)")
    p.add_argument("--workers", default="2")
    p.add_argument("--work", type=Path, default=Path("/tmp/stream"), help="the groups' folders")
    p.add_argument("--out", type=Path, default=Path("benchmarks/results/stream.json"))
    p.add_argument("--force", action="store_true")
    p.add_argument("--figure", type=Path, help="draw the combined figure into this .png")
    args = p.parse_args()
    earlier = {}
    if args.out.is_file():
        old = json.loads(args.out.read_text("utf-8")).get("measured", {}).get("groups", [])
        earlier = {g["command"]: g for g in old if "wall_seconds" in g}
    parts, commands = [], []
    for group in args.groups:
        folder = args.work / f"seeds-{group}"
        cmd = [
            "sigmapi",
            "stream",
            "--seeds",
            *map(str, _seeds(group)),
            "--traces",
            args.traces,
            "--dwells",
            args.dwells,
            "--workers",
            args.workers,
            "--out",
            str(folder),
            "--quiet",
            "--force",
        ]
        entry = {"command": " ".join(cmd), "load_avg_1min_before": os.getloadavg()[0]}
        if not args.force and (folder / "result.json").is_file():
            entry = earlier.get(entry["command"], entry)
        else:
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            start = time.perf_counter()
            exe = [sys.executable, "-m", "sigmapi.cli", *cmd[1:]]
            subprocess.run(exe, check=True, stdout=subprocess.DEVNULL)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            entry.update(
                wall_seconds=round(time.perf_counter() - start, 1),
                cpu_seconds=round(
                    after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime, 1
                ),
                load_avg_1min_after=os.getloadavg()[0],
            )
        commands.append(entry)
        parts.append(StreamResult.from_dict(read_result(folder)))
    result = StreamResult.combine(parts).to_dict()
    result["measured"] = {
        "command": " ".join(["python", "benchmarks/bench_stream.py", *sys.argv[1:]]),
        "groups": commands,
        "machine": f"{platform.machine()}, {os.cpu_count()} cores, shared (see the load averages)",
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2) + "\n", encoding="utf-8")
    combined = StreamResult.from_dict(result)
    print(combined.table())
    if args.figure is not None:
        from sigmapi.experiments.stream.figures import stream_figure

        stream_figure(result).savefig(args.figure, dpi=120)
        print(combined.caption())


if __name__ == "__main__":
    main()
