"""Cost of each integrator at its defaults on the settings the defaults are chosen for.

    python benchmarks/defaults_cost.py

The paper's settings (N = 5, μ = 0 and μ = 100, 5 s), and the stiff floor (κ_b = 1e5,
β = 1e-3) at N = 200, μ = 0 and 100 (1.2 s, the first bounce).  One Markdown row per
case and integrator: accepted and rejected steps, run time without compilation, and the
relative energy error (μ = 0: |E − E0|/|E0|; μ > 0: |E + dissipated − E0|/|E0|).
"""
from __future__ import annotations

import time

import numpy as np

import rodjit

STIFF = {"floor.kappa_b": 1e5, "floor.beta": 1e-3, "rod.N": 200, "time.t_end": 1.2}
CASES = {
    "paper, N = 5, μ = 0": ("paper-mu0", {}),
    "paper, N = 5, μ = 100": ("paper-mu100", {}),
    "stiff floor, N = 200, μ = 0": ("paper-mu0", STIFF),
    "stiff floor, N = 200, μ = 100": ("paper-mu100", STIFF),
}
INTEGRATORS = ("energy", "semi-implicit", "verlet")


def main() -> None:
    print("| case | integrator | steps | rejected | run time (s) | energy error |")
    print("|---|---|---|---|---|---|")
    for label, (preset, over) in CASES.items():
        for name in INTEGRATORS:
            cfg = rodjit.load_preset(preset).override({
                **over, "time.integrator": name, "output.snapshot_interval": 0.0,
                "output.diagnostics_interval": 0.01})
            if name == "verlet" and cfg.rod.mu > 0 and cfg.rod.N > 50:
                print(f"| {label} | {name} | not run: steps ∝ μN² (see Config.warnings) |||")
                continue
            rodjit.simulate(cfg.override({"time.t_end": 1e-3}))   # compile
            t0 = time.perf_counter()
            res = rodjit.simulate(cfg)
            wall = time.perf_counter() - t0
            d = res.diagnostics
            e = np.asarray(d["energy_total"]) + np.asarray(d["dissipated"])
            err = np.abs(e - e[0]).max() / abs(e[0])
            s = res.stats
            print(f"| {label} | {name} | {s['steps']} | {s['rejected_steps']} | {wall:.2f} "
                  f"| {err:.1e} |", flush=True)


if __name__ == "__main__":
    import warnings
    warnings.simplefilter("ignore", rodjit.config.ModelWarning)
    main()
