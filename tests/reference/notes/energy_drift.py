"""Energy drift over 200 s at mu = 0 (paper-mu0 setting, N = 5) per integrator and cfl."""
import json, sys, time
import numpy as np
import rodjit
for integ, cfl in [(a, float(c)) for a, c in (x.split(":") for x in sys.argv[1:])] if len(sys.argv) > 1 else [("verlet", 0.05), ("verlet", 0.025), ("verlet", 0.0125), ("semi-implicit", 0.05), ("energy", None)]:
    over = {"time.integrator": integ, "time.t_end": 200.0, "output.snapshot_interval": 0.0, "output.diagnostics_interval": 0.01}
    if cfl: over["time.cfl"] = cfl
    cfg = rodjit.load_preset("paper-mu0").override(over)
    t0 = time.perf_counter(); r = rodjit.simulate(cfg); wall = time.perf_counter() - t0
    d = r.diagnostics; E = d["total"] if "total" in d else None
    keys = list(d)
    tot = [k for k in keys if "total" in k][0]
    rel = (d[tot] - r.energy0) / abs(r.energy0)
    out = dict(integ=integ, cfl=cfl, steps=int(r.stats["steps"]), wall=wall, energy_error=r.energy_error(),
               drift_t5=float(rel[np.searchsorted(d["t"], 5.0)]), drift_t20=float(rel[np.searchsorted(d["t"], 20.0)]),
               drift_t100=float(rel[np.searchsorted(d["t"], 100.0)]), drift_t200=float(rel[-1]), E0=r.energy0)
    print(json.dumps(out), flush=True)
