"""Run the solver-speed benchmarks and print a one-line verdict per target.

    python benchmarks/run_all.py [--quick] [--all]

Each script prints its own table and writes benchmarks/results/<name>.json; this summary
is written to benchmarks/results/summary.json.  The scripts are independent: run one
alone with ``python benchmarks/bench_<name>.py``.  ``--all`` then also runs the other
benchmarks in this directory (HDF5 streaming, start-up of ``rodjit run``, accuracy against
cost, the energy integrator; ~10 min), each as its own process with its defaults.
"""
from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _util  # noqa: E402
import bench_cache  # noqa: E402
import bench_explicit  # noqa: E402
import bench_scipy  # noqa: E402
import bench_semi_implicit  # noqa: E402


# the other benchmarks in this directory (streaming, start-up, accuracy, the energy step,
# sweeps), run as they are
OTHERS = ("streaming_overhead.py", "startup.py", "bench_accuracy.py", "bench_energy.py",
          "bench_sweep.py")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smaller runs (a smoke test)")
    ap.add_argument("--all", action="store_true",
                    help="also run " + ", ".join(OTHERS) + " afterwards")
    args = ap.parse_args(argv)
    q = ["--quick"] if args.quick else []
    # the cache benchmark first: it uses fresh processes and its own cache directories,
    # and the others then find their kernels compiled
    cache = bench_cache.main(["--repeat", "1"] if args.quick else [])
    explicit = bench_explicit.main(q)
    semi = bench_semi_implicit.main(q)
    scipy = bench_scipy.main(q)

    rows = []
    for r in explicit:
        if r["target"] is not None:
            rows.append(["explicit N=1000 vs C", r["variant"], f"{r['ratio']:.2f}x C",
                         f"<= {r['target']}x", "yes" if r["meets_target"] else "NO"])
    for preset, s in scipy["settings"].items():
        for m in s["matched"]:
            got = f"{m['speedup']:.3g}x" if "speedup" in m else "no match"
            rows.append([f"{preset} vs SciPy {s['scipy_method']}", f"error <= {m['target']:.0e}",
                         got, f">= {scipy['target_speedup']:g}x",
                         "yes" if m.get("meets_target") else "NO"])
    prim = next(v for v in semi["scenarios"].values() if v["primary"])
    rows.append(["semi-implicit N=1000", "steps/s over mu x gamma",
                 f"{100 * prim['spread']:.2f} % spread", f"<= {100 * semi['tolerance']:g} %",
                 "yes" if prim["meets_target"] else "NO"])
    for c in cache:
        rows.append(["disk cache", c["case"],
                     f"{c['cold']['process_wall']:.1f} s cold, {c['warm']['process_wall']:.2f} s warm",
                     "warm: no compile", "yes" if c["warm_without_compiling"] else "NO"])
    print("\n== summary ==")
    print(_util.table(rows, ["benchmark", "case", "measured", "target", "met"]))
    path = _util.save("summary", {"quick": args.quick, "rows": [
        dict(zip(["benchmark", "case", "measured", "target", "met"], r)) for r in rows]})
    print(f"   -> {path}")
    if args.all:
        for script in OTHERS:
            print(f"\n== {script} ==", flush=True)
            subprocess.run([sys.executable, str(Path(__file__).resolve().parent / script)],
                           check=False)


if __name__ == "__main__":
    main()
