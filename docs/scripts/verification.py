"""The verification figures of the documentation, computed from fresh runs.

``python docs/scripts/verification.py DIR`` writes the PNGs into DIR (``docs/figures`` by
default) and, beside them, ``verification.json``: the numbers each figure measures and a
caption stating them, which the Verification page shows (docs/hooks/generate.py), so no
number on that page is typed by hand.  ``tests/test_docs.py`` runs the script and checks the
committed figures and numbers against a fresh run.  The runs are short (the paper's rod,
or free vibrations and impacts of at most 200 segments): the whole set takes about a
minute once the kernels are compiled.  The checks the figures illustrate are asserted by
the test suite (see the Verification page).
"""
from __future__ import annotations

import io
import json
import sys
import warnings
from pathlib import Path

import numpy as np

INTEGRATORS = ("verlet", "semi-implicit", "energy")


def _cfg(overrides):
    import rodjit
    return rodjit.Config().override(overrides)


def _runnable(cfg, name):
    """``cfg`` and its label, under cfl control where the integrator cannot honour its
    tolerance (verlet at large μ refuses to run so)."""
    try:
        cfg.check_runnable()
    except ValueError:
        return cfg.override({"time.control": "cfl"}), f"{name} (cfl)"
    return cfg, name


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
            cfg, label = _runnable(_cfg({"time.integrator": name, "rod.mu": mu,
                                         "time.t_end": 2.0}), name)
            d = rodjit.simulate(cfg).diagnostics
            e = np.asarray(d["energy_total"]) + np.asarray(d["dissipated"])
            rel = np.abs(e - e[0]) / abs(e[0])
            ax.semilogy(d["t"], np.maximum(rel, 1e-17), label=label, lw=1)
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


def _frequency(n, k, E):
    """ω_k measured on a free rod (g = 0) started in the discrete mode shape cos(kπx_i)
    with amplitude 1e-6: zero crossings of the modal coordinate (lumped-mass projection),
    the half period fitted over four periods.  Fixed verlet steps of a two-thousandth of
    the period: their frequency error (ω dt)²/24 ≈ 4e-7 is far below the space error."""
    import rodjit
    from rodjit.model.system import masses
    x = np.linspace(0.0, 1.0, n + 1)
    phi = np.cos(k * np.pi * x)
    period = 2 * np.pi / (k * np.pi * np.sqrt(E))
    cfg = _cfg({"rod.N": n, "gravity.g": 0.0, "time.integrator": "verlet",
                  "time.dt": period / 2000, "time.t_end": 4 * period,
                  "output.snapshot_interval": period / 400,
                  "output.diagnostics_interval": 0.0})
    res = rodjit.simulate(cfg, u0=1.0 + x + 1e-6 * phi)
    m = masses(n)
    q = ((res.u - (1.0 + x)) @ (m * phi)) / ((m * phi) @ phi)
    i = np.flatnonzero(np.sign(q[:-1]) != np.sign(q[1:]))
    t0 = res.t[i] - q[i] * (res.t[i + 1] - res.t[i]) / (q[i + 1] - q[i])
    return np.pi / np.polyfit(np.arange(t0.size), t0, 1)[0]


def modes(ax):
    """Free-free modal frequencies (γ = 0) against h: measured from free vibrations, the
    semi-discrete formula ω_k(h) = (2/h)√E sin(kπh/2) and the continuum kπ√E."""
    from rodjit.analysis import free_free_frequencies, wave_speed
    E = wave_speed(_cfg({})) ** 2
    ns = np.array([8, 16, 32, 64])
    h = 1.0 / ns
    fine = np.geomspace(h[0], h[-1], 50)
    dev, orders = [], {}
    for k, colour in zip((1, 2, 3), ("C0", "C1", "C2")):
        exact = k * np.pi * np.sqrt(E)
        measured = np.array([_frequency(int(n), k, E) for n in ns])
        semi = free_free_frequencies(ns, E, k)
        dev.append(np.max(np.abs(measured / semi - 1)))
        err = np.abs(measured / exact - 1)
        orders[k] = float(np.log2(err[-2] / err[-1]))
        ax.loglog(h, err, "o", color=colour, label=f"k = {k}: rodjit")
        ax.loglog(fine, np.abs(free_free_frequencies(1 / fine, E, k) / exact - 1), "-",
                  color=colour, lw=1, label=f"k = {k}: (2/h)√E sin(kπh/2)")
    ax.set_xlabel("h = 1/N")
    ax.set_ylabel("|ω_k / (kπ√E) − 1|")
    ax.set_title("free-free modes: measured, semi-discrete formula, continuum")
    ax.legend(fontsize=8)
    numbers = {"max_deviation_from_semi_discrete": float(max(dev)),
               **{f"order_k{k}": v for k, v in orders.items()}}
    caption = (f"N = 8, 16, 32, 64, modes k = 1, 2, 3: the measured frequencies agree with "
               f"the semi-discrete formula to {numbers['max_deviation_from_semi_discrete']:.1e} "
               f"(relative, at most), and converge to kπ√E at observed orders "
               + ", ".join(f"{orders[k]:.3f}" for k in (1, 2, 3))
               + " (finest pair, k = 1, 2, 3).")
    return numbers, caption


SPRING_ALPHAS = (1.0, 5.0, 10.0)
SPRING_LADDER = [25, 50, 100, 200]


def _spring_wall_config(alpha, E, V=1e-6):
    """MODEL.md §5's linear limit: g = 0, impact speed V ≪ c, the floor linearised,
    σ_b ≈ (3κ_b/β)(−u_0): spring constant k = 3κ_b/β = αE."""
    from rodjit.analysis import spring_wall_impact
    beta = 0.05
    s, _ = spring_wall_impact(alpha, 2000)
    return _cfg({"gravity.g": 0.0, "floor.kappa_b": alpha * E * beta / 3,
                   "floor.beta": beta, "initial.height": V * 1e-3, "initial.velocity": -V,
                   "time.t_end": 1e-3 + s / np.sqrt(E) + 0.02,
                   "output.snapshot_interval": 0.0, "output.diagnostics_interval": 1e-4,
                   "time.integrator": "verlet", "time.control": "cfl"})


def spring_wall(ax_time, ax_rest):
    """Contact time and restitution of the spring-wall impact against α = k/E: the
    d'Alembert solution and rodjit's values extrapolated along rod.N = 25 … 200."""
    import rodjit
    from rodjit.analysis import spring_wall_impact, wave_speed
    E = wave_speed(_cfg({})) ** 2
    c = np.sqrt(E)
    curve = np.geomspace(0.5, 30, 40)
    exact = np.array([spring_wall_impact(a, 1000) for a in curve])
    ax_time.semilogx(curve, exact[:, 0], "k-", lw=1, label="d'Alembert")
    ax_rest.semilogx(curve, exact[:, 1], "k-", lw=1, label="d'Alembert")
    numbers = {}
    rows = []
    for alpha in SPRING_ALPHAS:
        s, e = spring_wall_impact(alpha)
        conv = rodjit.converge(_spring_wall_config(alpha, E), {"rod.N": SPRING_LADDER},
                               observables=["contact_time_first", "restitution_first"],
                               also=False, scheduler="inline")   # the space ladder alone
        ct = conv["contact_time_first"].value * c
        rs = conv["restitution_first"].value
        coarse = conv["contact_time_first"].space.values[0] * c
        numbers[f"alpha{alpha:g}_contact_time_rel"] = float(ct / s - 1)
        numbers[f"alpha{alpha:g}_restitution_rel"] = float(rs / e - 1)
        rows.append(f"| {alpha:g} | {s:.6f} | {ct:.6f} | {ct / s - 1:+.1e} | {e:.6f} | "
                    f"{rs:.6f} | {rs / e - 1:+.1e} |")
        ax_time.semilogx([alpha], [coarse], "s", mfc="none", color="C1",
                         label="rodjit, N = 25" if alpha == SPRING_ALPHAS[0] else None)
        ax_time.semilogx([alpha], [ct], "o", color="C0",
                         label="rodjit, extrapolated" if alpha == SPRING_ALPHAS[0] else None)
        ax_rest.semilogx([alpha], [rs], "o", color="C0",
                         label="rodjit, extrapolated" if alpha == SPRING_ALPHAS[0] else None)
    ax_time.set_ylabel("c · T_contact")
    ax_rest.set_ylabel("restitution")
    for ax in (ax_time, ax_rest):
        ax.set_xlabel("α = k/E")
        ax.legend(fontsize=8)
    ax_time.set_title("spring-wall impact: contact time")
    ax_rest.set_title("spring-wall impact: restitution")
    caption = ("Richardson-extrapolated along rod.N = "
               + ", ".join(map(str, SPRING_LADDER)) + " (fixed-fraction verlet steps):\n\n"
               "| α = k/E | c·T (d'Alembert) | c·T (rodjit) | relative | e (d'Alembert) | "
               "e (rodjit) | relative |\n|---|---|---|---|---|---|---|\n" + "\n".join(rows))
    return numbers, caption


SAINT_VENANT_KAPPA_B = (10.0, 100.0, 1e3, 1e4, 1e5)
SAINT_VENANT_N = (50, 200)


def saint_venant(ax_time, ax_rest):
    """The rigid-wall limit: a bar at 0.01 m/s (g = 0, μ = 0) on an ever stiffer floor,
    contact time c·T/2 and restitution against the floor's stiffness ratio α = 3κ_b/(βE),
    beside the linear spring-wall solution; both tend to 1 (Saint-Venant: T = 2/c)."""
    import rodjit
    from rodjit.analysis import spring_wall_impact, wave_speed
    E = wave_speed(_cfg({})) ** 2
    c = np.sqrt(E)
    beta = 0.05
    alphas = np.array([3 * kb / (beta * E) for kb in SAINT_VENANT_KAPPA_B])
    # the delay equation's trapezoidal steps need α·ds small, so the curve stops at α = 200
    # (25 Python-loop solves of 2000 steps per transit; the dashed line is the limit)
    curve = np.geomspace(alphas[0], 200.0, 25)
    exact = np.array([spring_wall_impact(a, 2000) for a in curve])
    ax_time.semilogx(curve, exact[:, 0] / 2, "k-", lw=1, label="linear spring (d'Alembert)")
    ax_rest.semilogx(curve, exact[:, 1], "k-", lw=1, label="linear spring (d'Alembert)")
    numbers = {}
    for n, marker in zip(SAINT_VENANT_N, ("s", "o")):
        ts, es = [], []
        for kb in SAINT_VENANT_KAPPA_B:
            s, _ = spring_wall_impact(min(3 * kb / (beta * E), 200.0), 2000)
            cfg = _cfg({"rod.N": n, "floor.kappa_b": kb, "floor.beta": beta,
                          "gravity.g": 0.0, "initial.height": 1e-3,
                          "initial.velocity": -0.01, "time.t_end": 1e-1 + s / c + 0.02,
                          "output.snapshot_interval": 0.0,
                          "output.diagnostics_interval": 1e-3,
                          "time.integrator": "verlet", "time.control": "cfl"})
            b = rodjit.simulate(cfg).bounces
            ts.append((b["t_release"][0] - b["t_impact"][0]) * c / 2)
            es.append(b["restitution"][0])
        ax_time.semilogx(alphas, ts, marker, ms=5, mfc="none", label=f"rodjit, N = {n}")
        ax_rest.semilogx(alphas, es, marker, ms=5, mfc="none", label=f"rodjit, N = {n}")
        numbers[f"N{n}_half_contact_time_stiffest"] = float(ts[-1])
        numbers[f"N{n}_restitution_stiffest"] = float(es[-1])
    for ax in (ax_time, ax_rest):
        ax.axhline(1.0, color="0.6", lw=0.8, ls="--")
        ax.set_xlabel("α = 3κ_b/(βE)")
        ax.legend(fontsize=8)
    ax_time.set_ylabel("c · T_contact / 2")
    ax_rest.set_ylabel("restitution")
    ax_time.set_title("Saint-Venant limit: contact time → 2/c")
    ax_rest.set_title("Saint-Venant limit: restitution → 1")
    kb = SAINT_VENANT_KAPPA_B[-1]
    caption = (f"On the stiffest floor (κ_b = {kb:g}, α = {alphas[-1]:.3g}) the contact "
               f"lasts " + ", ".join(
                   f"{numbers[f'N{n}_half_contact_time_stiffest']:.4f} × 2/c (N = {n})"
                   for n in SAINT_VENANT_N)
               + ", and the restitution is " + ", ".join(
                   f"{numbers[f'N{n}_restitution_stiffest']:.4f} (N = {n})"
                   for n in SAINT_VENANT_N) + ".")
    return numbers, caption


def scipy_reference(ax_u, ax_err):
    """The paper's rod (N = 5, μ = 100) through its first bounce: every registered
    integrator at its defaults against SciPy's Radau (rtol 1e-10) on the semi-discrete
    system written out again in NumPy (tests/reference/fd_semidiscrete.py)."""
    import rodjit
    from rodjit.stepping.registry import NAMES
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
    from reference.fd_semidiscrete import FDSystem
    from reference.laws import Params
    from reference.trajectory import integrate_to
    t_end, every = 0.8, 0.005
    system = FDSystem(5, Params(mu=100.0))
    t = np.arange(1, int(round(t_end / every)) + 1) * every
    ref, coarser = (integrate_to(system.rhs, system.jac, system.initial(1.0), t, rtol=rtol,
                                 atol=rtol * 1e-2)[:, :6] for rtol in (1e-10, 1e-9))
    ax_u.plot(t, ref[:, 0], "k-", lw=1.5, label="SciPy Radau: u₀")
    ax_u.plot(t, ref[:, -1], "k--", lw=1, label="SciPy Radau: u_N")
    own = np.max(np.abs(coarser - ref), axis=1)
    numbers = {"radau_rtol_1e-9_vs_1e-10": float(own.max())}
    ax_err.semilogy(t, np.maximum(own, 1e-16), color="0.6", lw=1.5,
                    label="Radau rtol 1e-9 vs 1e-10")
    for name in NAMES:
        cfg, label = _runnable(_cfg({"rod.mu": 100.0, "time.integrator": name,
                                     "time.t_end": t_end, "output.snapshot_interval": every}),
                               name)
        res = rodjit.simulate(cfg)
        rows = np.searchsorted(res.t, t - 1e-12)
        err = np.max(np.abs(res.u[rows] - ref), axis=1)
        numbers[f"{name}_max_abs_u"] = float(err.max())
        ax_err.semilogy(t, np.maximum(err, 1e-16), lw=1, label=label)
        if name == rodjit.config.TimeConfig().integrator:
            ax_u.plot(res.t, res.u[:, 0], "o", ms=2, label=f"rodjit ({name}): u₀")
            ax_u.plot(res.t, res.u[:, -1], "o", ms=2, label=f"rodjit ({name}): u_N")
    ax_u.set_xlabel("t [s]")
    ax_u.set_ylabel("height [m]")
    ax_u.set_title("N = 5, μ = 100: the first bounce")
    ax_u.legend(fontsize=8)
    ax_err.set_xlabel("t [s]")
    ax_err.set_ylabel("max_i |u_i − u_i(Radau)| [m]")
    ax_err.set_title("difference from the SciPy solution")
    ax_err.legend(fontsize=8)
    caption = ("Largest difference of the node heights from the Radau solution over "
               f"t ≤ {t_end:g} s, each integrator at its default tolerances: "
               + ", ".join(f"`{n}` {numbers[f'{n}_max_abs_u']:.1e} m" for n in NAMES)
               + f"; the reference itself moves by {numbers['radau_rtol_1e-9_vs_1e-10']:.1e} m "
               "between rtol 1e-9 and 1e-10.")
    return numbers, caption


def _png(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    return buf.getvalue()


# file name -> (figure size, number of axes, the function drawing it).  A function that
# measures something returns (numbers, caption): the numbers go into NUMBERS_FILE and the
# caption, which states them, onto the Verification page (docs/hooks/generate.py).
FIGURES = {
    "free_fall.png": ((6, 3.6), 1, free_fall),
    "energy.png": ((10, 3.6), 2, energy),
    "convergence_dt.png": ((6, 3.6), 1, convergence),
    "modes.png": ((6.5, 4), 1, modes),
    "spring_wall.png": ((10, 3.6), 2, spring_wall),
    "saint_venant.png": ((10, 3.6), 2, saint_venant),
    "scipy_reference.png": ((10, 3.6), 2, scipy_reference),
}
NUMBERS_FILE = "verification.json"


def figures() -> tuple[dict[str, bytes], dict[str, dict]]:
    """``({file name: PNG bytes}, {file name: {"numbers": {...}, "caption": str}})``."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import rodjit
    pngs, measured = {}, {}
    with warnings.catch_warnings():
        # several checks are of the μ = γ = 0 model, or of verlet at μ = 100, on purpose
        warnings.simplefilter("ignore", rodjit.config.ModelWarning)
        for name, (size, n_axes, draw) in FIGURES.items():
            fig, axes = plt.subplots(1, n_axes, figsize=size, layout="constrained")
            out = draw(*np.atleast_1d(axes))
            if out is not None:
                numbers, caption = out
                measured[name] = {"numbers": numbers, "caption": caption}
            pngs[name] = _png(fig)
            plt.close(fig)
    return pngs, measured


if __name__ == "__main__":
    target = Path(sys.argv[1] if len(sys.argv) > 1 else "docs/figures")
    target.mkdir(parents=True, exist_ok=True)
    pngs, measured = figures()
    for name, png in pngs.items():
        (target / name).write_bytes(png)
        print(target / name)
    (target / NUMBERS_FILE).write_text(json.dumps(measured, indent=1, ensure_ascii=False)
                                       + "\n")
    print(target / NUMBERS_FILE)
