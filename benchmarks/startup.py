"""Start-up time of ``rodjit run`` on the default configuration, as a user sees it: a fresh
interpreter, import, kernels loaded from the Numba cache (warm) or compiled (cold, empty
``NUMBA_CACHE_DIR``), the run, the file and the summary.  Where the install built the
default run's loop ahead of time (``rodjit.stepping.aot``), neither: cold and warm differ
only by the cache directory.  Target: warm under 2 s.

The baseline is a bare ``python -c pass`` measured in the same session.

    python benchmarks/startup.py [--repeat 5]
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time


def wall(cmd, env, cwd) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, env=env, cwd=cwd, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    run = [sys.executable, "-m", "rodjit", "run", "-o", "default.h5", "--overwrite"]
    with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as work:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        python = min(wall([sys.executable, "-c", "pass"], env, work) for _ in range(args.repeat))
        cold = wall(run, env, work)                  # empty cache: compiles every kernel
        imp = min(wall([sys.executable, "-c", "import rodjit, rodjit.cli"], env, work)
                  for _ in range(args.repeat))
        warm = [wall(run, env, work) for _ in range(args.repeat)]
    warm.sort()
    print(f"python -c pass                 {python:6.2f} s")
    print(f"import rodjit, rodjit.cli      {imp:6.2f} s")
    print(f"rodjit run (warm cache)        {warm[0]:6.2f} s best, {warm[len(warm) // 2]:.2f} s "
          f"median of {args.repeat}  (target < 2 s)")
    print(f"rodjit run (cold, empty cache) {cold:6.2f} s")
    print(f"warm start = {warm[0] / python:.1f}x a bare interpreter start")


if __name__ == "__main__":
    main()
