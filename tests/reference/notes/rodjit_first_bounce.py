"""rodjit semi-implicit / verlet / energy: first bounce vs dt (fixed) and at defaults."""
import sys, time, json
import rodjit
def run(integ, mu, N, **over):
    cfg = rodjit.load_preset("paper-mu100").override({"rod.mu": mu, "rod.N": N, "time.integrator": integ,
        "output.snapshot_interval": 0.0, "output.diagnostics_interval": 0.0, "time.t_end": 1.2, **over})
    t0 = time.perf_counter(); r = rodjit.simulate(cfg); wall = time.perf_counter() - t0
    b = r.bounces
    return dict(e=float(b["restitution"][0]), tc=float(b["t_release"][0]-b["t_impact"][0]),
                u0=float(b["min_u0"][0]), eps=float(b["min_strain"][0]), steps=int(r.stats["steps"]), wall=wall)
def main():
  which = sys.argv[1]
  if which == "defaults":
      for integ in ["semi-implicit", "energy"]:
          for mu in [1, 100, 1000]:
              for N in [5, 50, 200]:
                  print(json.dumps(dict(integ=integ, mu=mu, N=N, **run(integ, mu, N))), flush=True)
  elif which == "ladder":
      N = int(sys.argv[2]); mu = float(sys.argv[3])
      for dt in [float(x) for x in sys.argv[4].split(",")]:
          print(json.dumps(dict(integ="semi-implicit", mu=mu, N=N, dt=dt, **run("semi-implicit", mu, N, **{"time.dt": dt}))), flush=True)
  elif which == "cfl":
      N = int(sys.argv[2]); mu = float(sys.argv[3]); integ = sys.argv[4]
      for cfl in [0.05, 0.02, 0.01, 0.005, 0.0025]:
          print(json.dumps(dict(integ=integ, mu=mu, N=N, cfl=cfl, **run(integ, mu, N, **{"time.cfl": cfl}))), flush=True)

if __name__ == "__main__":
    main()
