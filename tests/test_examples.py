"""Every script in examples/ runs to completion (quick mode) and writes what it says."""
from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXPECTED = {
    "paper_figures.py": ["paper-mu0.h5", "paper-mu100.h5", "paper_mu0.png", "paper_mu100.png"],
    "sweep_mu.py": ["sweep_mu.h5", "sweep_mu.png"],
    "convergence.py": ["convergence.h5"],
    "custom_observer.py": ["apex_sweep.h5"],
}


def test_every_example_is_tested():
    assert sorted(p.name for p in (ROOT / "examples").glob("*.py")) == sorted(EXPECTED)


def _tracked_files() -> dict[str, int] | None:
    """The repository's tracked files and their modification times (None outside a git
    checkout)."""
    try:
        proc = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True,
                              text=True, timeout=60)
    except OSError:
        return None
    if proc.returncode != 0 or not proc.stdout:
        return None
    return {p: (ROOT / p).stat().st_mtime_ns for p in proc.stdout.split("\0")
            if p and (ROOT / p).is_file()}


SLOW = ("sweep_mu.py", "custom_observer.py")


@pytest.mark.parametrize("script", [pytest.param(s, marks=pytest.mark.slow) if s in SLOW
                                    else s for s in sorted(EXPECTED)])
def test_example_runs(script, tmp_path):
    """Run as a user does (no argument: the current directory), it writes its files there
    and no file of the repository changes (docs/ included)."""
    pytest.importorskip("matplotlib")
    pytest.importorskip("xarray")
    source = (ROOT / "examples" / script).read_text()
    assert not re.search(r"""["'](\.\./)*docs/""", source), "an example writes into docs/"
    before = _tracked_files()
    env = {**os.environ, "RODJIT_EXAMPLES_QUICK": "1"}
    proc = subprocess.run([sys.executable, str(ROOT / "examples" / script)],
                          capture_output=True, text=True, timeout=600, env=env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    for name in EXPECTED[script]:
        assert (tmp_path / name).stat().st_size > 0, name
    if before is not None:
        after = _tracked_files()
        assert [p for p in before if before[p] != after.get(p)] == []
