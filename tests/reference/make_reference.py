"""Compute the first-bounce reference values and write reference_values.json beside this file.

    .venv/bin/python tests/reference/make_reference.py            # everything (a few minutes)
    .venv/bin/python tests/reference/make_reference.py --quick    # N = 5 only
    # on two cores: two sections in parallel, then merged (nothing recomputed)
    .venv/bin/python tests/reference/make_reference.py --only semi_discrete &
    .venv/bin/python tests/reference/make_reference.py --only continuum,liftoff --out /tmp/b.json
    .venv/bin/python tests/reference/make_reference.py --resume --merge /tmp/b.json

Setting: the paper's μ = 100 setting (data/paper_mu100.toml: κ = 100, κ_b = 1000, β = 0.05,
g = −9.81, γ = 0, dropped from height 1 at rest, t_end = 5) with μ ∈ {1, 100, 1000} and
N ∈ {5, 50, 200}.  Semi-discrete values (MODEL.md §2, ``fd_semidiscrete``) at each N from
SciPy Radau at a tolerance ladder rtol = 1e-9, 1e-11 (atol = rtol/100): the value is the
tight one, the error estimate the difference between the two.  Continuum values
(``p2fe``) from P2 elements with 10 and 20 elements at rtol = 1e-9 (the value is the finer one, the
estimate the difference).  μ = 10 and 30 are run as well to record whether the rod lifts off
before t_end at all.
"""
from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np
import scipy

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from reference.fd_semidiscrete import FDSystem  # noqa: E402
from reference.laws import Params  # noqa: E402
from reference.p2fe import P2System  # noqa: E402
from reference.trajectory import first_bounce  # noqa: E402

SETTING = dict(kappa=100.0, gamma=0.0, kappa_b=1000.0, beta=0.05, g=-9.81, height=1.0,
               t_end=5.0)
OBSERVABLES = ("restitution", "contact_time", "min_u0", "min_strain", "t_impact",
               "t_release", "w_impact", "w_release")
LADDER = (1e-9, 1e-11)
ATOL_FACTOR = 1e-2


def _params(mu):
    s = SETTING
    return Params(kappa=s["kappa"], gamma=s["gamma"], mu=mu, kappa_b=s["kappa_b"],
                  beta=s["beta"], g=s["g"])


def _run(system, rtol):
    fb = first_bounce(system.rhs, system.jac, system.initial(SETTING["height"]),
                      SETTING["t_end"], system.probes(), rtol=rtol, atol=rtol * ATOL_FACTOR)
    return fb.as_dict()


def _entry(runs):
    """Value = the last (most accurate) run; estimate = |difference to the one before|."""
    coarse, fine = runs[-2], runs[-1]
    entry = {"closed": fine["closed"], "released": fine["released"],
             "n_episodes": fine["n_episodes"], "t_apex": fine["t_apex"],
             "values": {k: fine[k] for k in OBSERVABLES},
             "error_estimate": {k: abs(fine[k] - coarse[k]) for k in OBSERVABLES},
             "cost": [{k: r[k] for k in ("steps", "nfev", "njev", "nlu", "wall")}
                      for r in runs]}
    return entry


def semi_discrete(n, mu):
    system = FDSystem(n, _params(mu))
    runs = []
    for rtol in LADDER:
        runs.append(_run(system, rtol))
        print(f"  FD N={n} mu={mu} rtol={rtol:g}: e={runs[-1]['restitution']:.12g} "
              f"({runs[-1]['wall']:.1f} s)", flush=True)
    return _entry(runs) | {"rtol": list(LADDER)}


def continuum(mu, meshes=(10, 20), rtol=1e-9):
    runs = []
    for ne in meshes:
        runs.append(_run(P2System(ne, _params(mu)), rtol))
        print(f"  P2 Ne={ne} mu={mu}: e={runs[-1]['restitution']:.12g} "
              f"({runs[-1]['wall']:.1f} s)", flush=True)
    return _entry(runs) | {"elements": list(meshes), "rtol": rtol}


def liftoff(n, mu, rtol=1e-9):
    r = _run(FDSystem(n, _params(mu)), rtol)
    return {k: r[k] for k in ("closed", "released", "n_episodes", "t_impact", "t_release",
                              "min_u0", "wall")}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="N = 5 only, no continuum")
    ap.add_argument("--out", default=str(HERE / "reference_values.json"))
    ap.add_argument("--resume", action="store_true",
                    help="keep the entries already in --out, compute only the missing ones")
    ap.add_argument("--merge", nargs="*", default=[], metavar="FILE",
                    help="also keep the entries of these files (made by this script)")
    ap.add_argument("--only", default="semi_discrete,continuum,liftoff",
                    help="comma-separated sections to compute")
    args = ap.parse_args(argv)
    out = Path(args.out)
    only = set(args.only.split(","))
    old = {"semi_discrete": {}, "continuum": {}, "liftoff": {}}
    for path in ([out] if args.resume and out.exists() else []) + [Path(m) for m in args.merge]:
        for section, entries in json.loads(path.read_text()).items():
            if section in old:
                old[section].update(entries)
    ns = (5,) if args.quick else (5, 50, 200)
    mus = (1.0, 100.0, 1000.0)
    tic = time.perf_counter()
    data = {
        "description": "First bounce (MODEL.md §3) on the paper's mu = 100 setting with "
                       "other mu: semi-discrete (MODEL.md §2) and continuum (P2 FE) "
                       "references, made by tests/reference/make_reference.py",
        "setting": SETTING,
        "solver": {"semi_discrete": "tests/reference/fd_semidiscrete.py, scipy Radau, "
                                    "analytic sparse Jacobian",
                   "continuum": "tests/reference/p2fe.py, P2 elements, consistent mass, "
                                "scipy Radau",
                   "ladder_rtol": list(LADDER), "atol": f"rtol * {ATOL_FACTOR:g}",
                   "scipy": scipy.__version__, "numpy": np.__version__,
                   "python": platform.python_version()},
        "semi_discrete": {}, "continuum": {}, "liftoff": {},
    }
    def put(section, key, make):
        """Compute one entry (or keep the stored one) and write the file at once, so an
        interrupted run keeps what it finished."""
        if key in old[section]:
            data[section][key] = old[section][key]
        elif section in only:
            data[section][key] = make()
        data["wall_seconds"] = time.perf_counter() - tic
        out.write_text(json.dumps(data, indent=1, sort_keys=False) + "\n")

    for n in ns:
        for mu in mus:
            put("semi_discrete", f"N={n},mu={mu:g}",
                lambda: semi_discrete(n, mu) | {"N": n, "mu": mu})
    if not args.quick:
        for mu in mus:
            put("continuum", f"mu={mu:g}", lambda: continuum(mu) | {"mu": mu})
        for n in (5, 200):
            for mu in (10.0, 30.0):
                put("liftoff", f"N={n},mu={mu:g}", lambda: liftoff(n, mu) | {"N": n, "mu": mu})
                print(f"  liftoff N={n} mu={mu}: {data['liftoff'].get(f'N={n},mu={mu:g}')}",
                      flush=True)
    print(f"wrote {out} in {data['wall_seconds']:.0f} s")


if __name__ == "__main__":
    main()
