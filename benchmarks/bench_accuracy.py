"""Accuracy against cost of the explicit schemes: energy error and first restitution vs cfl.

    python benchmarks/bench_accuracy.py

The paper's first setting (N = 5, μ = 0) over 10 s (~15 bounces) and the second (μ = 100)
over 5 s.  The reference restitution comes from a fixed step of 2e-6 s.  Writes
benchmarks/results/accuracy.json.
"""
import json
import time
from pathlib import Path

import rodjit
from rodjit.presets import load_preset

CFLS = (0.4, 0.2, 0.1, 0.05, 0.025, 0.0125)


def main():
    rows = []
    ref = rodjit.simulate(load_preset("paper-mu0").override({"time.t_end": 1.0, "time.dt": 2e-6}))
    e_ref = ref.bounces["restitution"][0]
    for preset, t_end in (("paper-mu0", 10.0), ("paper-mu100", 5.0)):
        for integrator in ("verlet", "semi-implicit"):
            for cfl in CFLS:
                cfg = load_preset(preset).override({"time.t_end": t_end, "time.cfl": cfl, "time.control": "cfl",
                                                    "time.integrator": integrator,
                                                    "output.snapshot_interval": 0.0})
                t0 = time.perf_counter()
                res = rodjit.simulate(cfg)
                wall = time.perf_counter() - t0
                row = {"preset": preset, "integrator": integrator, "cfl": cfl,
                       "steps": res.stats["steps"], "bounces": res.n_bounces,
                       "energy_error": res.energy_error(), "run_time": res.stats["run_time"],
                       "wall_time": wall}
                if preset == "paper-mu0":
                    row["restitution_1_error"] = abs(res.bounces["restitution"][0] / e_ref - 1)
                rows.append(row)
                print(f"{preset:12s} {integrator:14s} cfl {cfl:<7g} steps {row['steps']:>8d} "
                      f"energy error {row['energy_error']:.2e}"
                      + (f"  |e1/e1_ref - 1| {row['restitution_1_error']:.1e}"
                         if "restitution_1_error" in row else "")
                      + f"  run {row['run_time'] * 1e3:.1f} ms")
    out = Path(__file__).parent / "results" / "accuracy.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps({"reference_restitution_1": e_ref, "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
