"""The paper's two figures: heights of the six division points of the rod (N = 5, γ = 0)
against time: a chaotic, energy-conserving motion at μ = 0 and decay to rest at μ = 100.

    python examples/paper_figures.py [OUTDIR]        # writes paper_mu0.png, paper_mu100.png

RODJIT_EXAMPLES_QUICK=1 shortens the runs to 0.5 s (the test suite runs it so).
"""
import os
import sys
from pathlib import Path

import rodjit
import rodjit.plotting

QUICK = os.environ.get("RODJIT_EXAMPLES_QUICK") == "1"


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    out.mkdir(parents=True, exist_ok=True)

    for preset in ("paper-mu0", "paper-mu100"):
        cfg = rodjit.load_preset(preset)
        if QUICK:
            cfg = cfg.override({"time.t_end": 0.5})
        run = out / f"{preset}.h5"
        summary = rodjit.run_to_file(cfg, run, overwrite=True)
        png = rodjit.plotting.plot_file(run, out / f"{preset.replace('-', '_')}.png")
        print(f"{preset}: {summary.report().splitlines()[0]} -> {png}")


if __name__ == "__main__":   # the sweep's workers import this file (spawn)
    main()
