"""How long the command line takes to start: ``sigmapi --version``, ``--help`` and ``presets``
against ``import sigmapi``, in fresh processes (median of ``--repeats``), with the heavy modules
each one imported.

    python benchmarks/bench_startup.py [--repeats 5] [--baseline-src OLD/src]

With ``--baseline-src`` another checkout's ``src`` (e.g. ``git archive COMMIT src | tar -x -C
/tmp/old``) is measured too, the code bases alternating, so that a loaded machine weighs on
both alike. Prints one JSON object (CPU seconds are the child's user + system time; the wall
clock is shown beside them as the machine is shared); writes nothing.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
HEAVY = ("numba", "matplotlib", "sklearn", "mujoco", "dask")
_CLI = "from sigmapi.cli import main\ntry:\n    main({argv!r})\nexcept SystemExit:\n    pass"
COMMANDS = {
    "import sigmapi": "import sigmapi",
    "sigmapi --version": _CLI.format(argv=["--version"]),
    "sigmapi --help": _CLI.format(argv=["--help"]),
    "sigmapi presets": _CLI.format(argv=["presets"]),
}
REPORT = (
    f"\nimport sys\nprint('HEAVY', [m for m in {HEAVY!r} if m in sys.modules], file=sys.stderr)"
)


def _once(code: str, src: Path) -> tuple[float, float, list[str]]:
    env = {**os.environ, "PYTHONPATH": str(src)}
    t0, r0 = time.perf_counter(), os.times()
    r = subprocess.run([sys.executable, "-c", code + REPORT], env=env, capture_output=True,
                       text=True, check=True, cwd="/")  # fmt: skip
    r1 = os.times()
    cpu = r1.children_user - r0.children_user + r1.children_system - r0.children_system
    line = next(x for x in r.stderr.splitlines() if x.startswith("HEAVY"))
    return time.perf_counter() - t0, cpu, json.loads(line[6:].replace("'", '"'))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--baseline-src", type=Path)
    args = ap.parse_args()
    bases = {"this": SRC, **({"baseline": args.baseline_src} if args.baseline_src else {})}
    runs: dict[str, dict[str, list[tuple[float, float, list[str]]]]] = {
        b: {c: [] for c in COMMANDS} for b in bases
    }
    for _ in range(args.repeats):
        for name, code in COMMANDS.items():
            for base, src in bases.items():
                runs[base][name].append(_once(code, src))
    out = {
        base: {
            name: {
                "wall_s": round(statistics.median(r[0] for r in rs), 3),
                "cpu_s": round(statistics.median(r[1] for r in rs), 3),
                "heavy_imported": rs[-1][2],
            }
            for name, rs in per.items()
        }
        for base, per in runs.items()
    }
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
