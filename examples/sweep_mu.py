"""A sweep over the viscosity μ on the paper's μ = 100 setting, analysed with xarray: the
first bounce's restitution and contact time against μ.

    python examples/sweep_mu.py [OUTDIR]             # writes sweep_mu.h5 and sweep_mu.png

RODJIT_EXAMPLES_QUICK=1 sweeps three values over a shorter run (the test suite runs it so).
"""
import os
import sys
from pathlib import Path

import numpy as np
import rodjit

QUICK = os.environ.get("RODJIT_EXAMPLES_QUICK") == "1"


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    out.mkdir(parents=True, exist_ok=True)

    base = rodjit.load_preset("paper-mu100").override(
        {"time.integrator": "energy", "time.t_end": 1.0 if QUICK else 3.0})
    mus = [0.1, 1.0, 100.0] if QUICK else list(np.logspace(-1, 3, 9))
    rodjit.sweep(base, {"rod.mu": mus}, output=out / "sweep_mu.h5", jobs=1 if QUICK else None,
                 overwrite=True)

    ds = rodjit.load_sweep(out / "sweep_mu.h5").to_xarray()      # dimension mu, attrs key rod.mu
    assert (ds["status"] == "completed").all(), ds["message"].values
    print(ds[["restitution_first", "contact_time_first", "min_u0"]].to_dataframe())

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.5), layout="constrained")
    ds["restitution_first"].plot(ax=a, marker="o", xscale="log")
    ds["contact_time_first"].plot(ax=b, marker="o", xscale="log")
    a.set_title("restitution of the first bounce")
    b.set_title("duration of the first contact")
    fig.savefig(out / "sweep_mu.png", dpi=120)
    print(out / "sweep_mu.png")


if __name__ == "__main__":   # the sweep's workers import this file (spawn)
    main()
