"""The default test run again with NumPy's and numba's SIMD paths limited (slow, CI's second step).

A test that asserts bit equality of floating-point results computed on another machine (a pinned
value, a file in ``tests/data``) passes on the machine it was written on and fails on a CPU
whose SIMD path sums in another order: an AMD EPYC without AVX-512 failed the README's test
command by one ulp this way. Running the suite on the baseline path here (every NumPy dispatch
target off, numba compiling for a generic x86-64) makes such an assertion fail on every machine,
before a user meets it. Floating-point comparisons across machines state a tolerance and its
reason instead (``tests/model/test_files.py``: ``CROSS_MACHINE_ULPS``).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _numpy_dispatch_targets() -> list[str]:
    """The SIMD targets this NumPy dispatches to at run time (the baseline cannot be disabled)."""
    try:
        from numpy._core import _multiarray_umath as umath
    except ImportError:  # NumPy 1.x
        from numpy.core import _multiarray_umath as umath  # type: ignore[no-redef]
    return list(umath.__cpu_dispatch__)


@pytest.mark.slow
def test_the_default_suite_passes_on_the_baseline_simd_path(tmp_path):
    env = dict(os.environ)
    env["NPY_DISABLE_CPU_FEATURES"] = " ".join(_numpy_dispatch_targets())
    env["NUMBA_CPU_NAME"] = "generic"
    env.pop("NUMBA_CPU_FEATURES", None)
    probe = subprocess.run(
        [sys.executable, "-c", "import numpy, numba; print(numpy.__version__)"],
        env=env, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert probe.returncode == 0, probe.stderr  # the variables themselves are accepted
    run = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "--basetemp",
         str(tmp_path / "t"), "-m", "not slow"],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=3600,
    )  # fmt: skip
    tail = "\n".join((run.stdout + run.stderr).splitlines()[-40:])
    assert run.returncode == 0, f"the suite on the baseline SIMD path:\n{tail}"
    assert " passed" in tail
