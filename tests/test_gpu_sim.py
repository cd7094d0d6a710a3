"""The GPU engine in numba-cuda's simulator, against the CPU path: the same sweep's table.

The simulator must be chosen before ``numba.cuda`` is first imported, and other tests in
the same worker import it for real (tests/test_gpu_ptx.py), so each check runs in a fresh
process with ``NUMBA_ENABLE_CUDASIM=1``.  There the kernel's threads run as Python and call
the CPU's compiled loop (``rodjit.gpu.kernel``): the same algorithm on the same CPU, so
the table agrees to rounding (1e-9 relative is asserted; on a GPU, NVVM fuses other
multiply-adds than LLVM does, so there too agreement is to rounding, not bit for bit).  The
compile of the GPU's own code is checked by tests/test_gpu_ptx.py.
"""
from __future__ import annotations

import importlib.util
import json

import pytest

from conftest import run_simulated

if importlib.util.find_spec("numba_cuda") is None:
    pytest.skip("the GPU engine's extra is not installed: pip install 'rodjit[cuda]'",
                allow_module_level=True)


# the timings; every other column, the first-impact ones the GPU streams from its
# diagnostics rows (rodjit.stepping.impact_stream) included, is compared
NOT_COMPARED = {"wall_time", "compile_time", "run_time"}

SCRIPT = """
import json, sys
import numpy as np
import rodjit
from rodjit.sweeps import load_sweep

integrator, out = sys.argv[1], sys.argv[2]
cfg = rodjit.Config().override({"time.t_end": 0.6, "rod.mu": 5.0,
                                "time.integrator": integrator})
# one point per kind of end: completed with a bounce, and failed (dt_min far too large)
grid = {"floor.kappa_b": [1000.0, 3000.0], "time.dt_min": [1e-12, 2e-3]}
gpu = rodjit.sweep(cfg, grid, output=out, device="cuda", progress=False)
cpu = rodjit.sweep(cfg, grid, scheduler="inline", progress=False)
back = load_sweep(out)
report = {"status": list(map(str, gpu.columns["status"])), "differ": {}, "file": {},
          "impact": list(map(str, gpu.columns["impact_status"])),
          "worker": gpu.stats.get("backend"), "bounces": {}}
for name, a in gpu.columns.items():
    b = cpu.columns[name]
    if a.dtype.kind == "f":
        same = np.allclose(a, b, rtol=1e-9, atol=0, equal_nan=True)
    else:
        same = bool((a == b).all())
    if not same:
        report["differ"][name] = [str(a.tolist()), str(b.tolist())]
    c = back.columns[name]
    if a.dtype.kind == "f":
        kept = np.array_equal(a, c, equal_nan=True)
    else:
        kept = bool((a == c).all())
    if not kept:
        report["file"][name] = [str(a.tolist()), str(c.tolist())]
for i in range(len(gpu.grid)):
    bg, bc = gpu.bounces(i), cpu.bounces(i)
    for name in bc:
        x, y = np.asarray(bg[name]), np.asarray(bc[name])
        ok = (np.allclose(x, y, rtol=1e-9, atol=0, equal_nan=True) if x.dtype.kind == "f"
              else np.array_equal(x, y))
        if not ok:
            report["bounces"][f"{i}.{name}"] = [str(x.tolist()), str(y.tolist())]
# the engine's own product, as the batch engines hand it to the driver
from rodjit.gpu.engine import run_batch
from rodjit.records.columns import BOUNCE_COLUMNS
from rodjit.sweeps.point import empty_columns
b = run_batch([gpu.grid.config(gpu.base, i) for i in (2, 0)], [2, 0])
want = empty_columns(2)
report["batch"] = {
    "index": b.index.tolist(), "dtypes": all(b.values[k].dtype == want[k].dtype for k in want),
    "keys": sorted(b.values) == sorted(want) and sorted(b.bounces) == sorted(BOUNCE_COLUMNS),
    "rows": int(b.bounce_count.sum()) == len(b.bounces["t_impact"]),
    "same": [float(b.values["restitution_first"][0]),
             float(gpu.columns["restitution_first"][2])]}
print(json.dumps(report))
"""


@pytest.mark.parametrize("integrator", ["energy", pytest.param("dp54", marks=pytest.mark.slow)])
def test_gpu_sweep_matches_cpu(tmp_path, integrator):
    """energy (the default, implicit) and dp54 (explicit, adaptive, dense output): every
    summary column the GPU computes, and every bounce record, as the CPU's; the sweep file
    holds the GPU's table."""
    p = run_simulated(["-c", SCRIPT, integrator, str(tmp_path / "s.h5")])
    assert p.returncode == 0, p.stderr[-3000:]
    report = json.loads(p.stdout.strip().splitlines()[-1])
    assert report["status"] == ["completed", "failed", "completed", "failed"]
    # the first contact is read from the streamed diagnostics, not left undefined
    assert "undefined" not in report["impact"], report["impact"]
    assert report["worker"] == "cuda"
    assert set(report["differ"]) <= NOT_COMPARED, report["differ"]
    assert not report["bounces"], report["bounces"]
    assert not report["file"], report["file"]
    batch = report["batch"]
    assert batch["index"] == [2, 0] and batch["dtypes"] and batch["keys"] and batch["rows"]
    assert batch["same"][0] == batch["same"][1]


def test_cli_device_cuda(tmp_path):
    """``rodjit sweep --device cuda`` writes the sweep file; N above the limit, run files
    and a scheduler are refused with one line and exit code 2, before any file is made."""
    out = tmp_path / "c.h5"
    p = run_simulated(["-m", "rodjit", "sweep", "--device", "cuda", "--set", "time.t_end=0.2",
                    "--grid", "floor.kappa_b=1000,3000", "-o", str(out), "-q"])
    assert p.returncode == 0, p.stderr[-3000:]
    from rodjit.sweeps import load_sweep

    table = load_sweep(out)
    assert list(table.columns["status"]) == ["completed", "completed"]
    assert (table.columns["steps"] > 0).all()
    bad = tmp_path / "n.h5"
    p = run_simulated(["-m", "rodjit", "sweep", "--device", "cuda", "--set", "rod.N=65",
                    "--grid", "floor.kappa_b=1000,3000", "-o", str(bad)])
    assert p.returncode == 2
    err = p.stderr.strip().splitlines()
    assert len(err) == 1 and "rod.N = 65" in err[0] and "1 to 64" in err[0], p.stderr
    assert not bad.exists()
    p = run_simulated(["-m", "rodjit", "sweep", "--device", "cuda", "--save-runs",
                    str(tmp_path / "runs"), "--grid", "floor.kappa_b=1000,3000", "-o", str(bad)])
    assert p.returncode == 2
    err = p.stderr.strip().splitlines()
    assert len(err) == 1 and "--save-runs" in err[0], p.stderr
    assert not bad.exists()
    p = run_simulated(["-m", "rodjit", "sweep", "--device", "cuda", "--scheduler", "local",
                    "--grid", "floor.kappa_b=1000,3000", "-o", str(bad)])
    assert p.returncode == 2
    err = p.stderr.strip().splitlines()
    assert len(err) == 1 and "--scheduler" in err[0], p.stderr
    assert not bad.exists()


FULL_SCRIPT = """
import json
import numpy as np
import rodjit
import rodjit.gpu.engine as G
from rodjit.sweeps.point import PointTask, run_point, SUMMARY_COLUMNS

G.BOUNCE_ROWS = 1                 # a thread keeps one bounce row
cfg = rodjit.Config().override({"time.t_end": 2.0})
gpu = rodjit.sweep(cfg, {"initial.height": [0.1, 0.2]}, device="cuda", progress=False)
report = {"n_bounces": gpu.columns["n_bounces"].tolist(), "differ": []}
for i in range(len(gpu.grid)):
    ref = run_point(PointTask(i, gpu.grid.config(gpu.base, i), None, ()))
    for name in SUMMARY_COLUMNS:
        if name in ("wall_time", "compile_time", "run_time"):
            continue
        a, b = gpu.columns[name][i], ref.values[name]
        if not (a == b or (isinstance(b, float) and np.isnan(a) and np.isnan(b))):
            report["differ"].append(f"{i}.{name}: {a!r} {b!r}")
    got = gpu.bounces(i)
    for name, col in ref.bounces.items():
        x, y = np.asarray(got[name]), np.asarray(col)
        if not np.array_equal(x, y, equal_nan=y.dtype.kind == "f"):
            report["differ"].append(f"{i}.bounces.{name}")
print(json.dumps(report))
"""


def test_a_point_with_more_bounces_than_a_thread_keeps_has_them_all():
    """A thread whose bounce rows are full stops, and its point runs again on the CPU
    engine: every bounce is in its table, and its row is the per-point path's (no bounce
    dropped, ``n_bounces`` the point's own)."""
    p = run_simulated(["-c", FULL_SCRIPT])
    assert p.returncode == 0, p.stderr[-3000:]
    report = json.loads(p.stdout.strip().splitlines()[-1])
    assert min(report["n_bounces"]) > 2, report
    assert not report["differ"], report["differ"]
