"""Energy over 200 s at mu = 0 (paper-mu0, N = 5) for verlet with fixed steps."""
import json, time, numpy as np, rodjit
for dt in [1e-4, 5e-5]:
    cfg = rodjit.load_preset("paper-mu0").override({"time.integrator": "verlet", "time.t_end": 200.0, "time.dt": dt,
        "output.snapshot_interval": 0.0, "output.diagnostics_interval": 0.01})
    t0 = time.perf_counter()
    try:
        r = rodjit.simulate(cfg)
    except Exception as e:
        print(json.dumps(dict(dt=dt, error=str(e)[:200]))); continue
    d = r.diagnostics; tot = [k for k in d if "total" in k][0]; rel = (d[tot] - r.energy0) / abs(r.energy0)
    print(json.dumps(dict(integ="verlet-fixed", dt=dt, steps=int(r.stats["steps"]), wall=time.perf_counter() - t0,
        energy_error=r.energy_error(), drift_t200=float(rel[-1]), max_abs=float(np.abs(rel).max()))), flush=True)
