"""Runs, files, checkpoints and a sweep table equal, bit for bit, the goldens written by
``tests/golden/make_golden.py`` with the code they pin (see that script's docstring)."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent / "golden"))
import make_golden  # noqa: E402

GOLDEN = Path(__file__).parent / "golden"


def _compare(new: dict, golden_path: Path) -> None:
    with np.load(golden_path) as gold:
        gold = dict(gold)
    missing = sorted(set(gold) - set(new))
    assert not missing, f"{golden_path.name}: missing {missing}"
    for name, want in gold.items():
        got = new[name]
        if name == "config":
            got_cfg, want_cfg = json.loads(str(got)), json.loads(str(want))
            changed = {k: (got_cfg.get(k), v) for k, v in want_cfg.items()
                       if got_cfg.get(k) != v}
            assert not changed, f"{golden_path.name}: configuration differs: {changed}"
            continue
        assert got.dtype == want.dtype, f"{golden_path.name}:{name} dtype {got.dtype} != {want.dtype}"
        assert got.shape == want.shape, f"{golden_path.name}:{name} shape {got.shape} != {want.shape}"
        equal_nan = want.dtype.kind == "f"
        assert np.array_equal(got, want, equal_nan=equal_nan), f"{golden_path.name}:{name} differs"


@pytest.mark.parametrize("name", list(make_golden.CASES))
def test_run_file_matches_golden(name, tmp_path):
    path = tmp_path / f"{name}.h5"
    make_golden.write_run(name, path)
    _compare(make_golden.extract(path), GOLDEN / f"{name}.npz")


@pytest.mark.parametrize("name", make_golden.RESUMED)
def test_resumed_run_matches_golden(name, tmp_path):
    path = tmp_path / f"{name}_resumed.h5"
    make_golden.write_resumed(name, path)
    _compare(make_golden.extract(path), GOLDEN / f"{name}_resumed.npz")


def test_sweep_matches_golden(tmp_path):
    path = tmp_path / "sweep.h5"
    make_golden.write_sweep(path)
    _compare(make_golden.extract(path), GOLDEN / "sweep.npz")


def test_golden_comparison_detects_a_change(tmp_path):
    """The comparison is not vacuous: one bit of one value changed is caught."""
    path = tmp_path / "verlet_mu0.h5"
    make_golden.write_run("verlet_mu0", path)
    data = make_golden.extract(path)
    u = data["snapshots/u"].copy()
    u[3, 2] = np.nextafter(u[3, 2], np.inf)
    data["snapshots/u"] = u
    with pytest.raises(AssertionError, match="snapshots/u"):
        _compare(data, GOLDEN / "verlet_mu0.npz")
