"""Smoke test of an installed rodjit: three integrators, a resume, a sweep, from the command line.

Run it with the Python of the environment under test (``venv/bin/python .ci/smoke.py DIR``);
it calls that environment's ``rodjit`` script, writes into DIR, and checks that each command
exits 0 and that the files it wrote hold physically sensible results (energy conserved at
mu = 0, energy balance at mu > 0, the semi-implicit and energy integrators agreeing, bounces
found). ``--expect-site`` also checks that rodjit is imported from that environment (a wheel
install, not a source tree); ``--expect-aot`` that the install built the default run's loop
ahead of time and that the default run uses it, without importing Numba. Used by ``.ci/run`` for the minimum-versions and the wheel
environments; short runs, so the time goes mostly into compiling the kernels.
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

import numpy as np


def sh(*args: str, cwd: Path) -> None:
    t0 = time.perf_counter()
    print("+ rodjit", " ".join(args), flush=True)
    done = subprocess.run([str(RODJIT), *args], cwd=cwd)
    if done.returncode != 0:
        sys.exit(f"smoke: `rodjit {' '.join(args)}` exited {done.returncode}")
    print(f"  ({time.perf_counter() - t0:.1f} s)", flush=True)


def check(ok: bool, what: str) -> None:
    if not ok:
        sys.exit(f"smoke: {what}")
    print(f"  ok: {what}", flush=True)


def energy_error(res) -> float:
    """Largest |E(t) + dissipated(t) - E(0)| / |E(0)| over the diagnostics rows."""
    d = res.diagnostics
    e = np.asarray(d["energy_total"]) + np.asarray(d["dissipated"])
    return float(np.max(np.abs(e - e[0])) / abs(e[0]))


def main() -> None:
    global RODJIT
    ap = argparse.ArgumentParser()
    ap.add_argument("workdir", type=Path)
    ap.add_argument("--expect-site", action="store_true",
                    help="rodjit must be imported from this environment, not a source tree")
    ap.add_argument("--expect-aot", action="store_true",
                    help="the install built the ahead-of-time loop, and the default run uses it")
    ns = ap.parse_args()
    RODJIT = Path(sys.executable).parent / "rodjit"
    work = ns.workdir.resolve()
    work.mkdir(parents=True, exist_ok=True)

    import rodjit
    print(f"rodjit {rodjit.__version__} from {Path(rodjit.__file__).parent}", flush=True)
    if ns.expect_site:
        inside = Path(rodjit.__file__).resolve().is_relative_to(Path(sys.prefix).resolve())
        check(inside, f"rodjit imported from the environment {sys.prefix}")

    from rodjit.driver.run import Run
    from rodjit.stepping import aot

    uses_aot = Run(rodjit.Config())._aot is not None
    print(f"ahead-of-time loop: {'used' if uses_aot else 'not used'} (record "
          f"{aot.extension_record() is not None and 'present' or 'absent'})", flush=True)
    if ns.expect_aot:
        check(uses_aot, "the default run uses the ahead-of-time loop built at install")
        t0 = time.perf_counter()
        sh("run", "--t-end", "0.01", "-o", "first.h5", "--overwrite", "--quiet", cwd=work)
        first = time.perf_counter() - t0
        check(first < 10.0, f"the default run's process took {first:.1f} s (< 10 s: "
                            f"nothing compiled)")
        probe = subprocess.run(
            [sys.executable, "-c", "import sys, rodjit; rodjit.simulate(rodjit.Config()"
             ".override({'time.t_end': 0.01})); print('numba' in sys.modules)"],
            cwd=work, capture_output=True, text=True)
        check(probe.returncode == 0 and probe.stdout.split()[-1:] == ["False"],
              "the default run never imports Numba")

    sh("presets", cwd=work)
    # the presets run on energy; these two runs name their integrators, as the checks do
    sh("run", "paper-mu0", "-o", "mu0.h5", "--overwrite", "--quiet", "--t-end", "1",
       "--set", "time.integrator=verlet", cwd=work)
    sh("run", "--resume", "mu0.h5", "--t-end", "1.5", "--quiet", cwd=work)
    sh("run", "paper-mu100", "-o", "semi.h5", "--overwrite", "--quiet", "--t-end", "1",
       "--set", "time.integrator=semi-implicit", cwd=work)
    sh("run", "paper-mu100", "-o", "energy.h5", "--overwrite", "--quiet", "--t-end", "1",
       "--set", "time.integrator=energy", cwd=work)
    sh("sweep", "paper-mu100", "--grid", "rod.mu=0,100", "--set", "time.t_end=0.8",
       "--jobs", "2", "-o", "sweep.h5", "--overwrite", "--quiet", cwd=work)
    for name in ("mu0.h5", "semi.h5", "energy.h5", "sweep.h5"):
        subprocess.run([str(RODJIT), "info", name], cwd=work, check=True,
                       stdout=subprocess.DEVNULL)

    mu0 = rodjit.load_file(work / "mu0.h5")
    check(mu0.status == "completed" and abs(mu0.t_final - 1.5) < 1e-9,
          f"verlet run resumed to t = 1.5 (status {mu0.status}, t = {mu0.t_final})")
    check(len(mu0.bounces["restitution"]) >= 1, "verlet run: the rod bounced")
    check(energy_error(mu0) < 1e-2, f"verlet, mu = 0: energy drift {energy_error(mu0):.2e} < 1e-2")
    semi = rodjit.load_file(work / "semi.h5")
    energy = rodjit.load_file(work / "energy.h5")
    for name, res in (("semi-implicit", semi), ("energy", energy)):
        check(res.status == "completed", f"{name} run completed")
        check(energy_error(res) < 1e-2,
              f"{name}, mu = 100: energy balance error {energy_error(res):.2e} < 1e-2")
    n = min(len(semi.t), len(energy.t))
    gap = float(np.max(np.abs(semi.u[:n] - energy.u[:n])))
    check(n > 100 and np.allclose(semi.t[:n], energy.t[:n]) and gap < 1e-2,
          f"semi-implicit and energy heights agree at {n} snapshots (max gap {gap:.1e})")
    table = rodjit.load_sweep(work / "sweep.h5")
    check(list(table["status"]) == ["completed", "completed"], "sweep: both points completed")
    check(bool(np.all(np.asarray(table["n_bounces"]) >= 1)), "sweep: both points bounced")

    try:
        import matplotlib  # noqa: F401
    except ImportError:
        print("matplotlib not installed: plot skipped")
    else:
        sh("plot", "mu0.h5", "-o", "mu0.png", cwd=work)
        check((work / "mu0.png").stat().st_size > 1000, "plot written")
    try:
        import distributed  # noqa: F401
    except ImportError:
        print("dask.distributed not installed: Dask sweep skipped")
    else:
        sh("sweep", "paper-mu100", "--grid", "rod.mu=0,100", "--set", "time.t_end=0.8",
           "--jobs", "2", "--scheduler", "local", "-o", "sweep-dask.h5", "--overwrite",
           "--quiet", cwd=work)
        dask_table = rodjit.load_sweep(work / "sweep-dask.h5")
        check(np.array_equal(np.asarray(dask_table["n_bounces"]), np.asarray(table["n_bounces"])),
              "Dask sweep: same bounce counts as the process pool")
    print("smoke: all checks passed", flush=True)


if __name__ == "__main__":
    main()
