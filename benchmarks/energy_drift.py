"""Energy over 200 s at μ = 0 (the paper-mu0 setting) for each integrator at its defaults,
and the long-run statistics of the motion (apex heights, per-bounce restitution and
energy restitution over the bounces not marked ambiguous).

    python benchmarks/energy_drift.py [--t-end 200] [INTEGRATOR ...]

Prints one Markdown row per integrator: steps, run time, the largest relative energy
error |E − E0|/|E0| up to t = 5, 20, 100 and t_end, then the statistics of the run.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

import rodjit


def run(integrator: str, t_end: float):
    cfg = rodjit.load_preset("paper-mu0").override({
        "time.integrator": integrator, "time.t_end": t_end,
        "output.snapshot_interval": 0.0, "output.diagnostics_interval": 0.01})
    rodjit.simulate(cfg.override({"time.t_end": 0.01}))      # compile outside the timing
    t0 = time.perf_counter()
    res = rodjit.simulate(cfg)
    wall = time.perf_counter() - t0
    d = res.diagnostics
    t = np.asarray(d["t"])
    e = np.asarray(d["energy_total"])
    rel = np.abs(e - e[0]) / abs(e[0])
    drift = [rel[t <= tt + 1e-9].max() for tt in (5.0, 20.0, 100.0, t_end)]
    return res, wall, drift


def stats(res):
    """Per-bounce restitution and energy restitution of the bounces not marked ambiguous,
    the number of ambiguous ones, and the apex of the centre of mass in each flight after
    a closed bounce (from the diagnostics, every 0.01)."""
    b = res.bounces
    closed = ~np.asarray(b["open"])
    sure = ~np.asarray(b["ambiguous"])
    e = np.asarray(b["restitution"])[sure]
    e_energy = np.asarray(b["restitution_energy"])[sure]
    d = res.diagnostics
    t = np.asarray(d["t"])
    z = np.asarray(d["cm_height"])
    rel = np.asarray(b["t_release"])[closed]
    imp = np.append(np.asarray(b["t_impact"])[1:], np.inf)[closed]
    apex = np.array([z[(t >= r) & (t <= i)].max() for r, i in zip(rel, imp)
                     if np.any((t >= r) & (t <= i))])
    return e, e_energy, int((~sure).sum()), apex


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("integrators", nargs="*", default=["auto", "energy", "verlet", "semi-implicit"])
    ap.add_argument("--t-end", type=float, default=200.0)
    a = ap.parse_args()
    print("| integrator | steps | run time (s) | max rel. energy error to t = 5 / 20 / 100 / "
          f"{a.t_end:g} |")
    print("|---|---|---|---|")
    for name in a.integrators:
        res, wall, drift = run(name, a.t_end)
        print(f"| {name} | {res.stats['steps']} | {wall:.1f} | "
              + " / ".join(f"{x:.1e}" for x in drift) + " |", flush=True)
        e, e_energy, n_amb, apex = stats(res)
        line = (f"  bounces {e.size} ({n_amb} ambiguous left out): restitution mean "
                f"{e.mean():.3f} std {e.std():.3f} min {e.min():.2e} max {e.max():.3g}; "
                f"restitution_energy mean {e_energy.mean():.3f} std {e_energy.std():.3f} "
                f"min {e_energy.min():.3f} max {e_energy.max():.3f}")
        if apex.size:
            line += (f"; apex mean {apex.mean():.3f} std {apex.std():.3f} "
                     f"min {apex.min():.3f} max {apex.max():.3f}")
        print(line, flush=True)


if __name__ == "__main__":
    main()
