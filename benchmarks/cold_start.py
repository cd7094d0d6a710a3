"""What a fresh install pays before the first step: cold and warm `rodjit run` per
integrator, and which compiled functions the cold compile spends its time in.

Per integrator (``time.integrator`` of the default run, data/paper_mu0.toml): a fresh
process runs ``rodjit run paper-mu0 --t-end 0.01`` with NUMBA_CACHE_DIR an empty temporary
directory (cold), then twice more with the cache it filled (warm); the process wall time is
measured from outside.  Where the install built the loop ahead of time
(``rodjit.stepping.aot``: the integrators ``time.integrator = "auto"`` chooses, ``dop853``
and ``radau5``), their runs use it and compile nothing; ``dop853/jit`` runs the same
integrator on the JIT (``RODJIT_AOT=0``), which is what every other integrator does.  The
table says which loop each run used.  A second cold process per integrator records
Numba's compile events (``numba.core.event``, "numba:compile"): each compiled function's
inclusive time, and its exclusive time (inclusive minus the compiles nested inside it, i.e.
of the functions it calls), so the table shows where the time goes.

The baseline, measured in the same run: the *Numba floor*, a process that imports Numba and
calls one cached one-line kernel (warm: loaded from the cache), the least any Numba program
pays here before its first compiled call.  Warm starts are printed as ratios against it.
Also the *import floor*, a process that imports NumPy and h5py only (what a run on the
ahead-of-time loop, which never imports Numba, cannot go below).
Numba imports SciPy's linear algebra (``numba.np.linalg.ensure_blas``) the first time any
compiled function is used, whenever SciPy is installed, so the floor and the warm starts
depend on whether it is; the header says which (rodjit itself does not need SciPy).

    python benchmarks/cold_start.py [--integrators dop853,radau5,energy] [--out NAME]
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _util  # noqa: E402

RECORD = textwrap.dedent("""
    import json, sys, time
    from numba.core import event
    stack, rows = [], {}
    class L(event.Listener):
        def on_start(self, ev):
            stack.append([time.perf_counter(), 0.0])
        def on_end(self, ev):
            t0, child = stack.pop()
            dt = time.perf_counter() - t0
            if stack:
                stack[-1][1] += dt
            d = ev.data["dispatcher"]
            name = d.py_func.__module__ + "." + d.py_func.__qualname__
            r = rows.setdefault(name, [0.0, 0.0, 0])
            r[0] += dt; r[1] += dt - child; r[2] += 1
    event.register("numba:compile", L())
    t0 = time.perf_counter()
    from rodjit.cli import main
    try:
        main(["run", "paper-mu0", "--t-end", "0.01", "-q", "--overwrite", "-o", sys.argv[2],
              "--set", "time.integrator=" + sys.argv[1]], standalone_mode=False)
    except SystemExit:
        pass
    total = time.perf_counter() - t0
    from rodjit.driver.run import Run
    from rodjit.presets import load_preset
    cfg = load_preset("paper-mu0").override({"time.integrator": sys.argv[1]})
    print(json.dumps({"total": total, "rows": rows, "aot": Run(cfg)._aot is not None}))
""")


def _split(case: str) -> tuple[str, bool]:
    """``(integrator, jit_only)`` of a case name (``energy/jit``: on the JIT)."""
    name, _, how = case.partition("/")
    return name, how == "jit"


def _compiling_env(cache: Path, jit_only: bool = False) -> dict:
    """This process's environment for a child that compiles into the cache ``cache``
    (``jit_only``: with the ahead-of-time loop turned off)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    env.pop("NUMBA_DISABLE_JIT", None)
    env.pop("RODJIT_AOT", None)
    if jit_only:
        env["RODJIT_AOT"] = "0"
    return env


def cli_run(cache: Path, case: str, out: Path) -> float:
    integrator, jit_only = _split(case)
    env = _compiling_env(cache, jit_only)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "rodjit", "run", "paper-mu0", "--t-end", "0.01",
                    "-q", "--overwrite", "-o", str(out), "--set",
                    f"time.integrator={integrator}"], env=env, check=True, timeout=3600)
    return time.perf_counter() - t0


FLOOR = textwrap.dedent("""
    import numba

    @numba.njit(cache=True)
    def one(x):
        return x + 1.0

    one(1.0)
""")


def numba_floor(tmp: Path, repeats: int = 3) -> list[float]:
    """Wall times of ``repeats`` warm processes running the floor (module docstring)."""
    script = tmp / "floor.py"
    script.write_text(FLOOR)
    env = _compiling_env(tmp / "floor-cache")
    times = []
    for k in range(repeats + 1):      # the first one fills the cache
        t0 = time.perf_counter()
        subprocess.run([sys.executable, str(script)], env=env, check=True, timeout=600)
        if k:
            times.append(time.perf_counter() - t0)
    return times


def import_floor(repeats: int = 3) -> list[float]:
    """Wall times of ``repeats`` processes that import NumPy and h5py only: what any
    program that writes an HDF5 file from NumPy arrays pays here before its first line."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", "import numpy, h5py"], check=True, timeout=600)
        times.append(time.perf_counter() - t0)
    return times


def has_scipy() -> bool:
    p = subprocess.run([sys.executable, "-c", "import scipy"], capture_output=True)
    return p.returncode == 0


def recorded(cache: Path, case: str, out: Path) -> dict:
    integrator, jit_only = _split(case)
    env = _compiling_env(cache, jit_only)
    p = subprocess.run([sys.executable, "-c", RECORD, integrator, str(out)], env=env,
                       check=True, timeout=3600, capture_output=True, text=True)
    return json.loads(p.stdout.strip().splitlines()[-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--integrators", default="dop853,dop853/jit,radau5,radau5/jit,energy",
                    help="integrators (NAME/jit: on the JIT even where the install built "
                         "the ahead-of-time loop)")
    ap.add_argument("--top", type=int, default=12)
    ap.add_argument("--out", default="cold_start",
                    help="name of the results file (results/<out>.json)")
    args = ap.parse_args(argv)
    _util.header("cold start: rodjit run paper-mu0 --t-end 0.01, fresh Numba cache")
    scipy = has_scipy()
    with tempfile.TemporaryDirectory(prefix="rodjit-floor-") as tmp:
        floor = numba_floor(Path(tmp))
    base = sorted(floor)[len(floor) // 2]
    imports = import_floor()
    print(f"   SciPy installed: {'yes' if scipy else 'no'}; Numba floor (a cached one-line "
          f"kernel, warm process): {min(floor):.2f}–{max(floor):.2f} s; import floor "
          f"(NumPy and h5py): {min(imports):.2f}–{max(imports):.2f} s")
    results = {}
    for integ in args.integrators.split(","):
        with tempfile.TemporaryDirectory(prefix="rodjit-cold-") as tmp:
            tmp = Path(tmp)
            cold = cli_run(tmp / "cache", integ, tmp / "a.h5")
            warm = [cli_run(tmp / "cache", integ, tmp / "a.h5") for _ in range(2)]
        with tempfile.TemporaryDirectory(prefix="rodjit-cold-") as tmp:
            rec = recorded(Path(tmp) / "cache", integ, Path(tmp) / "a.h5")
        rows = sorted(rec["rows"].items(), key=lambda kv: -kv[1][1])
        compiled = sum(r[1] for _, r in rows)
        print(f"\n   {integ} ({'ahead-of-time loop' if rec['aot'] else 'JIT'}): cold "
              f"{cold:.1f} s, warm {min(warm):.2f}–{max(warm):.2f} s "
              f"({min(warm) / base:.2f}–{max(warm) / base:.2f}× the Numba floor); "
              f"recorded process {rec['total']:.1f} s, {len(rows)} functions compiled, "
              f"{compiled:.1f} s in Numba compiles")
        print(f"   targets: first step < 5 s cold {'✔' if cold < 5.0 else '✘'}, "
              f"< 1 s warm {'✔' if max(warm) < 1.0 else '✘'}")
        if rows:
            print("   " + _util.table([[n.replace("rodjit.", ""), r[1], r[0], r[2]]
                                       for n, r in rows[:args.top]],
                                      ["function", "exclusive s", "inclusive s", "compiles"])
                  .replace("\n", "\n   "))
        results[integ] = {"loop": "aot" if rec["aot"] else "jit",
                          "cold_seconds": cold, "warm_seconds": warm,
                          "recorded_total_seconds": rec["total"],
                          "compile_seconds": compiled,
                          "functions": {n: {"exclusive": r[1], "inclusive": r[0],
                                            "compiles": r[2]} for n, r in rows}}
        sys.stdout.flush()
    path = _util.save(args.out, {"scipy_installed": scipy, "numba_floor_seconds": floor,
                                 "import_floor_seconds": imports, "integrators": results})
    print(f"\nwrote {path}")


if __name__ == "__main__":
    main()
