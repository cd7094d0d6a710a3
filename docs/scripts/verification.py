"""The verification figures of the documentation, computed from fresh runs.

``figures()`` returns ``{file name: PNG bytes}``; the docs build (docs/hooks/generate.py)
calls it, and ``python docs/scripts/verification.py DIR`` writes the PNGs into DIR.  Every
run is the paper's short rod (N = 5), so the whole set takes seconds once the kernels are
compiled.  The checks these figures illustrate are asserted by the test suite (see the
Verification page).
"""
from __future__ import annotations

import io
import sys
from pathlib import Path

import numpy as np

INTEGRATORS = ("verlet", "semi-implicit", "energy")


def _cfg(overrides):
    import rodjit
    return rodjit.Config().override(overrides)


def free_fall(ax):
    """Bottom height before the first contact against u0(t) = h + g t²/2 (exact for KDK)."""
    import rodjit
    for name in INTEGRATORS:
        cfg = _cfg({"time.integrator": name, "time.t_end": 0.4, "time.dt": 1e-3,
                    "output.snapshot_interval": 0.01})
        res = rodjit.simulate(cfg)
        exact = cfg.initial.height + 0.5 * cfg.gravity.g * res.t ** 2
        err = np.abs(res.u[:, 0] - exact)
        ax.semilogy(res.t[1:], np.maximum(err[1:], 1e-17), "o-", ms=3, label=name)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("|u₀ − (h + g t²/2)| [m]")
    ax.set_title("free fall before the first contact (fixed dt = 1e-3)")
    ax.legend()


def energy(ax_mu0, ax_mu100):
    """μ = 0: relative energy drift; μ = 100: balance error E + D − E(0), both per integrator."""
    import rodjit
    for name in INTEGRATORS:
        for mu, ax in ((0.0, ax_mu0), (100.0, ax_mu100)):
            res = rodjit.simulate(_cfg({"time.integrator": name, "rod.mu": mu,
                                        "time.t_end": 2.0}))
            d = res.diagnostics
            e = np.asarray(d["energy_total"]) + np.asarray(d["dissipated"])
            rel = np.abs(e - e[0]) / abs(e[0])
            ax.semilogy(d["t"], np.maximum(rel, 1e-17), label=name, lw=1)
    ax_mu0.set_title("μ = 0: |E(t) − E(0)| / |E(0)|")
    ax_mu100.set_title("μ = 100: |E(t) + D(t) − E(0)| / |E(0)|")
    for ax in (ax_mu0, ax_mu100):
        ax.set_xlabel("t [s]")
        ax.legend()


def convergence(ax):
    """Fixed-step error of a vibrating rod in flight (pre-strain 0.1) against dt: slope 2."""
    import rodjit
    dts = 1e-3 / 2 ** np.arange(5)
    for name in INTEGRATORS:
        def end_state(dt):
            cfg = _cfg({"time.integrator": name, "time.t_end": 0.4, "time.dt": float(dt),
                        "initial.strain": 0.1, "output.snapshot_interval": 0.4})
            return rodjit.simulate(cfg).u[-1]
        ref = end_state(dts[-1] / 8)
        err = [np.max(np.abs(end_state(dt) - ref)) for dt in dts]
        ax.loglog(dts, err, "o-", label=name)
    ax.loglog(dts, 0.5 * err[0] * (dts / dts[0]) ** 2, "k--", lw=1, label="slope 2")
    ax.set_xlabel("dt [s]")
    ax.set_ylabel("max |u(0.4) − u_ref(0.4)| [m]")
    ax.set_title("second order in dt (fixed steps, rod in flight)")
    ax.legend()


def _png(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    return buf.getvalue()


def figures() -> dict[str, bytes]:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    out = {}
    fig, ax = plt.subplots(figsize=(6, 3.6), layout="constrained")
    free_fall(ax)
    out["free_fall.png"] = _png(fig)
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.6), layout="constrained")
    energy(a, b)
    out["energy.png"] = _png(fig)
    fig, ax = plt.subplots(figsize=(6, 3.6), layout="constrained")
    convergence(ax)
    out["convergence_dt.png"] = _png(fig)
    plt.close("all")
    return out


if __name__ == "__main__":
    target = Path(sys.argv[1] if len(sys.argv) > 1 else "docs/figures")
    target.mkdir(parents=True, exist_ok=True)
    for name, png in figures().items():
        (target / name).write_bytes(png)
        print(target / name)
