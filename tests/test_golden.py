"""Runs, files, checkpoints and a sweep table equal, bit for bit, the goldens written by
``tests/golden/make_golden.py`` with the code they pin (see that script's docstring), on a
machine whose CPU compiles the kernels as the one that wrote them; elsewhere to the
rounding by which CPUs that fuse multiply-adds differently can differ (``_close``)."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent / "golden"))
import make_golden  # noqa: E402

GOLDEN = Path(__file__).parent / "golden"


# Between CPUs that fuse multiply-adds differently: the largest difference of a value,
# relative to the largest magnitude of its array (measured 1e-11 between an Intel Xeon and
# an AMD EPYC over the goldens' one simulated second), and of the step sizes, which the
# adaptive integrators choose from error estimates that are themselves rounding-sized
# (5e-6 measured); step counts may differ by a rejected trial or two.
VALUE_RTOL = 1e-8
STEP_RTOL = 1e-3
COUNT_SLACK = 2
# the vibration energy at a rigid impact is a cancellation to rounding (about 1e-15 J)
ENERGY_ATOL = 1e-12


def _close(name: str, got: np.ndarray, want: np.ndarray) -> bool:
    """``got`` equals ``want`` to the rounding by which two CPUs can differ."""
    if want.dtype.kind in "iu":
        return bool(np.all(np.abs(got.astype(np.int64) - want.astype(np.int64))
                           <= np.maximum(COUNT_SLACK, 0.01 * np.abs(want))))
    if want.dtype.kind != "f":
        return bool(np.array_equal(got, want))
    if not np.array_equal(np.isnan(got), np.isnan(want)):
        return False
    ok = np.isfinite(want)
    if not np.array_equal(got[~ok & ~np.isnan(want)], want[~ok & ~np.isnan(want)]):
        return False
    if not ok.any():
        return True
    diff = np.abs(got[ok] - want[ok])
    rtol = STEP_RTOL if name.endswith("/dt") or name == "checkpoint:clock" else VALUE_RTOL
    atol = ENERGY_ATOL if name.endswith("energy_vibration_impact") else 0.0
    return bool(np.all(diff <= atol + rtol * np.max(np.abs(want[ok]))))


def _compare(new: dict, golden_path: Path) -> None:
    with np.load(golden_path) as gold:
        gold = dict(gold)
    exact = str(gold.pop("machine", "")) == make_golden.machine()
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
        if exact:
            equal_nan = want.dtype.kind == "f"
            assert np.array_equal(got, want, equal_nan=equal_nan), \
                f"{golden_path.name}:{name} differs"
        else:
            assert _close(name, got, want), \
                f"{golden_path.name}:{name} differs beyond rounding (golden from another CPU)"


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
    """The comparison is not vacuous: one bit of one value changed is caught on the CPU
    that wrote the golden; elsewhere (rounding tolerated) a change beyond rounding."""
    path = tmp_path / "verlet_mu0.h5"
    make_golden.write_run("verlet_mu0", path)
    data = make_golden.extract(path)
    u = data["snapshots/u"].copy()
    with np.load(GOLDEN / "verlet_mu0.npz") as gold:
        exact = str(gold["machine"]) == make_golden.machine()
    u[3, 2] = np.nextafter(u[3, 2], np.inf) if exact else u[3, 2] + 1e-6 * np.abs(u).max()
    data["snapshots/u"] = u
    with pytest.raises(AssertionError, match="snapshots/u"):
        _compare(data, GOLDEN / "verlet_mu0.npz")


def test_goldens_record_the_machine_that_wrote_them():
    """Every golden names its CPU, so the comparison knows when bits must match."""
    for path in sorted(GOLDEN.glob("*.npz")):
        with np.load(path) as gold:
            assert "machine" in gold and str(gold["machine"]).strip(), path.name


def test_comparison_across_cpus_tolerates_rounding_only():
    """Across CPUs: a value moved by rounding passes, one moved by more than rounding
    fails, a step count one rejected trial off passes, a changed shape fails."""
    want = np.array([1.0, -2.0, np.nan, 4.0])
    assert _close("snapshots/u", want * (1 + 1e-12), want)
    assert not _close("snapshots/u", want + np.array([0, 0, 0, 1e-6]), want)
    assert not _close("snapshots/u", np.array([1.0, -2.0, 0.0, 4.0]), want)
    assert _close("diagnostics/dt", want * (1 + 1e-5), want)
    assert _close("checkpoint:count", np.array([563, 87]), np.array([563, 86]))
    assert not _close("checkpoint:count", np.array([563, 96]), np.array([563, 86]))
    assert _close("bounces/energy_vibration_impact", np.array([1e-28]), np.array([-5e-15]))


def test_comparison_on_another_cpu_catches_a_change(tmp_path, monkeypatch):
    """On a machine unlike the golden's, a change beyond rounding is still caught."""
    monkeypatch.setattr(make_golden, "machine", lambda: "another CPU")
    path = tmp_path / "verlet_mu0.h5"
    make_golden.write_run("verlet_mu0", path)
    data = make_golden.extract(path)
    _compare(data, GOLDEN / "verlet_mu0.npz")
    data["snapshots/u"] = data["snapshots/u"] * (1 + 1e-6)
    with pytest.raises(AssertionError, match="snapshots/u"):
        _compare(data, GOLDEN / "verlet_mu0.npz")
