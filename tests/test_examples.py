"""Every script in examples/ runs to completion (quick mode) and writes what it says."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXPECTED = {
    "paper_figures.py": ["paper-mu0.h5", "paper-mu100.h5", "paper_mu0.png", "paper_mu100.png"],
    "sweep_mu.py": ["sweep_mu.h5", "sweep_mu.png"],
    "convergence.py": ["convergence.h5"],
}


def test_every_example_is_tested():
    assert sorted(p.name for p in (ROOT / "examples").glob("*.py")) == sorted(EXPECTED)


@pytest.mark.parametrize("script", sorted(EXPECTED))
def test_example_runs(script, tmp_path):
    pytest.importorskip("matplotlib")
    pytest.importorskip("xarray")
    env = {**os.environ, "RODJIT_EXAMPLES_QUICK": "1"}
    proc = subprocess.run([sys.executable, str(ROOT / "examples" / script), str(tmp_path)],
                          capture_output=True, text=True, timeout=600, env=env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    for name in EXPECTED[script]:
        assert (tmp_path / name).stat().st_size > 0, name
