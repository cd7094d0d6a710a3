"""A convergence study with rodjit.converge: the first bounce's observables on a ladder of
rod resolutions N (and a tolerance ladder at the second finest), extrapolated to the
continuum, with observed orders and error estimates.

    python examples/convergence.py [OUTDIR]          # writes convergence.h5

RODJIT_EXAMPLES_QUICK=1 uses a short, coarse ladder (the test suite runs it so).
"""
import os
import sys
from pathlib import Path

import rodjit

QUICK = os.environ.get("RODJIT_EXAMPLES_QUICK") == "1"


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    out.mkdir(parents=True, exist_ok=True)

    base = rodjit.load_preset("paper-mu100").override(
        {"time.integrator": "energy", "time.t_end": 1.0, "output.snapshot_interval": 0.0})
    ladder = {"rod.N": [5, 10, 20] if QUICK else [25, 50, 100, 200, 400]}
    also = {"time.rtol": [1e-5, 1e-6, 1e-7]} if not QUICK else None
    study = rodjit.converge(base, ladder, also=also, jobs=1 if QUICK else None)
    print(study)                                   # value ± error and observed order per observable
    study.save(out / "convergence.h5")
    print(sorted(rodjit.load_convergence(out / "convergence.h5")))


if __name__ == "__main__":   # the sweep's workers import this file (spawn)
    main()
