"""Compiled code cached on disk: start-up of a fresh process, cold and warm.

Each measurement is a new Python process with NUMBA_CACHE_DIR set to a temporary
directory: empty for the cold start, filled by the cold process for the warm starts.  The
process imports rodjit, builds a run and takes its first step; it reports the import time,
the time to the first step, ``Run.compile_time`` and the Numba cache hits and misses of the
compiled entry points (``start`` and ``advance``, which contain every other kernel).  The
process wall time (interpreter start-up included) is measured from outside.  A warm start
must show no cache misses.  The processes run on the JIT (``RODJIT_AOT=0``): the loop the
install compiles ahead of time for the default run uses no disk cache at all
(``cold_start.py`` measures it).

    python benchmarks/bench_cache.py [--repeat 3]
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

PROBE = textwrap.dedent("""
    import json, sys, time
    t0 = time.perf_counter()
    import rodjit
    from rodjit.driver.run import Run, Sink
    from rodjit.presets import load_preset
    from rodjit.stepping import loop
    t1 = time.perf_counter()
    run = Run(load_preset(sys.argv[1]).override(json.loads(sys.argv[2])))
    sink = Sink()
    run.start(sink)
    run.advance(sink, max_steps=1)
    t2 = time.perf_counter()
    assert run.steps == 1
    print(json.dumps({
        "import": t1 - t0, "first_step": t2 - t1, "compile_time": run.compile_time,
        "cache": {name: {"hits": sum(f.stats.cache_hits.values()),
                         "misses": sum(f.stats.cache_misses.values())}
                  for name, f in (("start", loop.start), ("advance", loop.advance))}}))
""")

# the integrator each preset runs with is its own (both: energy, the default)
CASES = {"paper-mu0 (the default run)": "paper-mu0",
         "paper-mu100": "paper-mu100"}


def probe(cache_dir: Path, preset: str, overrides: dict | None = None) -> dict:
    """One fresh process on ``preset`` (with configuration ``overrides``, e.g. another
    integrator) and the cache directory ``cache_dir``."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache_dir), RODJIT_AOT="0")
    env.pop("NUMBA_DISABLE_JIT", None)
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", PROBE, preset, json.dumps(overrides or {})],
                         env=env, capture_output=True, text=True, timeout=1800)
    wall = time.perf_counter() - t0
    if out.returncode != 0:
        raise RuntimeError(out.stderr[-3000:])
    res = json.loads(out.stdout.strip().splitlines()[-1])
    res["process_wall"] = wall
    res["misses"] = sum(c["misses"] for c in res["cache"].values())
    res["hits"] = sum(c["hits"] for c in res["cache"].values())
    return res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="warm starts (best kept)")
    args = ap.parse_args(argv)
    _util.header("Numba disk cache: fresh-process start, cold and warm")
    rows, results = [], []
    for label, preset in CASES.items():
        with tempfile.TemporaryDirectory(prefix="rodjit-numba-cache-") as tmp:
            cold = probe(Path(tmp), preset)
            warms = [probe(Path(tmp), preset) for _ in range(args.repeat)]
        warm = min(warms, key=lambda r: r["process_wall"])
        ok = all(w["misses"] == 0 and w["hits"] >= 2 for w in warms)
        for name, r in (("cold", cold), ("warm", warm)):
            rows.append([label, name, r["process_wall"], r["import"], r["first_step"],
                         r["compile_time"], r["hits"], r["misses"]])
        results.append({"case": label, "preset": preset, "cold": cold, "warm": warm,
                        "all_warm": warms, "warm_without_compiling": ok,
                        "cold_over_warm_process": cold["process_wall"] / warm["process_wall"]})
        print(f"   {label}: warm start without compiling: {'yes' if ok else 'NO'}; "
              f"process {cold['process_wall']:.2f} s cold -> {warm['process_wall']:.2f} s warm")
    print(_util.table(rows, ["case", "start", "process [s]", "import [s]",
                             "to 1st step [s]", "compile_time [s]", "cache hits",
                             "cache misses"]))
    path = _util.save("cache", {"repeat": args.repeat, "results": results})
    print(f"   -> {path}")
    return results


if __name__ == "__main__":
    main()
