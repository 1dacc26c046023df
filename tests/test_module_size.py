"""The house's rule on long modules (docs/guide/layout.md): a module of the library over 500
lines says at its top, in one comment, why it reads better as one."""

from __future__ import annotations

import re
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "sigmapi"
LIMIT = 500
REASON = re.compile(r"# Over \d+ lines: \S")


def test_every_module_over_the_limit_says_why_at_its_top() -> None:
    long = {}
    for path in sorted(SRC.rglob("*.py")):
        lines = path.read_text(encoding="utf-8").splitlines()
        if len(lines) > LIMIT:
            long[path.relative_to(SRC).as_posix()] = lines[0]
    assert long, "no module over the limit: the test would pass on anything; check SRC"
    missing = [f"{p} ({first!r})" for p, first in long.items() if not REASON.match(first)]
    assert not missing, (
        f"modules over {LIMIT} lines without '# Over N lines: why' as their first line: "
        + ", ".join(missing)
    )
