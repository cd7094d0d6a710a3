"""Work–precision of rodjit's six integrators over the regimes a default must cover: which
one is fastest at a given error, and what the default (the preset as a user runs it:
``time.integrator = "auto"`` at its tolerances) costs against it.

Settings (24): μ ∈ {0, 1, 100} × N ∈ {5, 20, 80, 320} × κ_b ∈ {1e3, 1e7}, named
``mu<μ>-N<N>-kb1e3`` / ``-kb1e7``.  κ_b = 1e3 is the preset's soft floor with its β = 0.05;
κ_b = 1e7 the stiff floor with β = 0.01.  Everything else is the paper preset's
(paper-mu0 with ``rod.mu`` overridden: h = 1 m drop from rest, κ = 100, γ = 0), over the
first second, T = 1 s (the fall, the first impact and its release), the state delivered
at the snapshot times 0, 0.005, …, 1 s and a diagnostics row at each (bench_peers'
``Problem``: the same configuration, snapshot times and error measure).

Error of a run, the larger of
  * the state error over the snapshots, bench_peers' ``Problem.error``: max(|u − u_ref|∞ /
    1 m, |v − v_ref|∞ / V), V = √(2|g|H) the impact speed, against bench_peers' tight
    reference, CyRK DOP853 at rtol = atol = 1e-13 (SciPy DOP853 if CyRK is missing) on
    bench_peers' independent right-hand side (``peer_rhs``); where μN² ≥ 1e6 (μ = 100,
    N = 320) an explicit method is stability-bound (CyRK DOP853 runs out of its 2e7 steps
    in the first 0.5 s) and the reference is SciPy Radau at rtol = atol = 1e-12 with
    bench_peers' banded Jacobian;
  * the first restitution's error |e − e_ref| (``Result.impact()["restitution_first"]``,
    located by the loop's contact events), e_ref from rodjit ``dop853`` at rtol = atol =
    1e-12 (``radau5`` where μN² ≥ 1e6; the peers have no contact events); where that
    run's first bounce is still open at T (μ = 100 on the stiff floor) the restitution is
    left out and the state error alone counts.  That run's
    state error against the peer reference is the reference check: a target is reported
    only if it is ≥ 10× that difference (bench_peers' rule).

Work: each integrator over its knob ladder, coarse to fine: rtol = atol ∈ {1e-3, …, 1e-9}
(a decade a rung) for energy, dp54, dop853 and radau5; ``time.control = "cfl"`` and
time.cfl ∈ {0.5, 0.16, 0.05, 0.016, 0.005, 0.0016, 5e-4} (half a decade a rung: error ∝
cfl², so a decade of error a rung) for verlet and semi-implicit, as bench_peers runs them.
Cost is ``Result.stats["run_time"]``, the compiled loop without compilation (every
integrator is compiled and warmed by a probe run first), best of 3 (of 1 for a run over
``--long`` seconds); steps and rejected steps are kept.  A ladder stops once a run's error
is below 0.3 × the finest target, or when the next rung is estimated over the budget
(``--budget``, 20 s: the last rung's time × the larger of the last rung-to-rung growth and
the growth of an order-p method's steps, 10^(1/p) per decade of tolerance, 1/cfl's for
cfl); the first rung is estimated from the probe, a run over the first 0.05 s, × 1/0.05.
An integrator whose configuration a run refuses (``Config.check_runnable``) is reported
"refused: <its reason>"; a rung skipped for time, "over budget".

At each target error E ∈ {1e-3, 1e-4, 1e-6} an integrator's cost is interpolated in
log-log along its cost–error Pareto front (bench_peers' ``front``/``cost_at``); the
fastest integrator is the one of least cost, and every other's ratio is its cost over the
fastest's.  The default is the preset as a user runs it (``auto``, which picks its
integrator per setting, at rtol = 1e-6, atol = 1e-9, the TimeConfig defaults): its error
E_d and cost are measured like a rung's,
and its ratio is its cost over the cheapest cost at E_d among all fronts (the default's
own point included, so the ratio is ≥ 1).

    python benchmarks/work_precision.py [--quick] [--settings mu0-N5-kb1e3,...] [--budget 20]

``--quick``: N ∈ {5, 20}, κ_b = 1e3, two rungs (1e-3 and 1e-6; cfl 0.5 and 0.016), about
a minute.  Results: ``benchmarks/results/work_precision.json`` (``work_precision_quick``
with --quick; ``--out`` names another), written after every setting, with the load average
before and after each setting.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _util  # noqa: E402
import bench_peers  # noqa: E402
from bench_peers import Problem, cost_at, front  # noqa: E402

import rodjit  # noqa: E402
from rodjit.config import ConfigError  # noqa: E402
from rodjit.stepping import registry  # noqa: E402

T_END = 1.0
MUS = (0.0, 1.0, 100.0)
NS = (5, 20, 80, 320)
FLOORS = {"kb1e3": (1e3, 0.05), "kb1e7": (1e7, 0.01)}
TARGETS = (1e-3, 1e-4, 1e-6)
INTEGRATORS = ("energy", "semi-implicit", "verlet", "dp54", "dop853", "radau5")
CFL_DRIVEN = bench_peers.CFL_DRIVEN
TOLS = tuple(10.0 ** -k for k in range(3, 10))                  # 1e-3 … 1e-9
CFLS = (0.5, 0.16, 0.05, 0.016, 0.005, 0.0016, 5e-4)
QUICK_RUNGS = (0, 3)                                              # 1e-3, 1e-6; cfl 0.5, 0.016
REF_TOL = 1e-12            # rodjit dop853 (radau5): the restitution's reference
# μN² from which the explicit reference is stability-bound (μ = 100, N = 320: CyRK DOP853
# ran out of its 2e7 steps in the first 0.5 s)
VISCOUS_STIFF = 1e6
PROBE_T = 0.05             # the probe run's span (s): compile, warm-up, first estimate
REPEATS = 3


def setting_names(quick: bool = False) -> list[str]:
    """The grid's settings in run order (N outermost: the short rods first, so a run cut
    short has measured whole rows of N), or the ``--quick`` subset."""
    ns = NS[:2] if quick else NS
    floors = ("kb1e3",) if quick else tuple(FLOORS)
    return [f"mu{mu:g}-N{n}-{fl}" for n in ns for fl in floors for mu in MUS]


def parse_setting(name: str) -> dict:
    """``mu100-N20-kb1e7`` → the overrides of paper-mu0 (rod.mu, rod.N, κ_b, β)."""
    try:
        mu, n, fl = name.split("-")
        if not (mu.startswith("mu") and n.startswith("N")) or fl not in FLOORS:
            raise ValueError
        kb, beta = FLOORS[fl]
        return {"rod.mu": float(mu[2:]), "rod.N": int(n[1:]), "floor.kappa_b": kb,
                "floor.beta": beta}
    except ValueError:
        raise ValueError(f"--settings: {name!r} is not mu<μ>-N<N>-kb1e3|kb1e7 "
                         f"(e.g. {setting_names()[0]})") from None


def ladder(integrator: str, quick: bool = False) -> tuple[str, tuple[float, ...]]:
    """``(knob, values)`` of an integrator's rungs, coarse to fine."""
    knob, values = ("cfl", CFLS) if integrator in CFL_DRIVEN else ("tol", TOLS)
    return knob, (tuple(values[i] for i in QUICK_RUNGS) if quick else values)


def overrides(integrator: str, knob: str, value: float) -> dict:
    """The configuration keys of one rung (as bench_peers.run_rodjit sets them)."""
    over = {"time.integrator": integrator}
    if knob == "cfl":
        over.update({"time.control": "cfl", "time.cfl": value})
    else:
        over.update({"time.rtol": value, "time.atol": value})
    return over


def next_estimate(times: list[float], values: list[float], knob: str, order: int,
                  value: float) -> float:
    """The estimated time of the rung at ``value`` from the measured rungs before it
    (``times`` at ``values``, coarse to fine, at least one): the last time × the larger of
    the last rung-to-rung growth and an order-``order`` method's step growth (tolerance:
    (v_last / value)^(1/order); cfl: v_last / value)."""
    last, v_last = times[-1], values[-1]
    growth = v_last / value if knob == "cfl" else (v_last / value) ** (1.0 / order)
    if len(times) > 1 and times[-2] > 0:
        growth = max(growth, last / times[-2])
    return last * growth


def run_error(state_error: float, e: float, e_ref: float) -> tuple[float, float | None]:
    """``(error, restitution error)`` of a run: the larger of its state error and
    |e − e_ref|; a run without a restitution where the reference has one has error inf;
    where the reference has none (its first bounce is still open at T), the restitution
    error is None and the state error alone counts."""
    if not math.isfinite(e_ref):
        return state_error, None
    de = abs(e - e_ref) if math.isfinite(e) else math.inf
    return max(state_error, de), de


def ratios_at(costs: dict[str, float | None]) -> dict | None:
    """At one target: ``{"fastest", "seconds", "runner_up", "runner_up_ratio", "ratios"}``
    from each integrator's interpolated cost (None: it does not reach the target); None if
    none reaches it.  ``ratios``: every integrator's cost over the fastest's (None where
    it does not reach the target)."""
    reached = sorted((c, name) for name, c in costs.items() if c is not None)
    if not reached:
        return None
    best, name = reached[0]
    runner = reached[1] if len(reached) > 1 else None
    return {"fastest": name, "seconds": best,
            "runner_up": runner and runner[1],
            "runner_up_ratio": runner and runner[0] / best,
            "ratios": {k: (None if c is None else c / best) for k, c in costs.items()}}


def default_ratio(fronts: dict[str, list], error: float, seconds: float) -> dict:
    """The default's cost over the cheapest cost at its own error ``error`` (its point
    ``(error, seconds)`` is a candidate too: the ratio is ≥ 1), and who is cheapest."""
    best, who = seconds, "default"
    for name, fr in fronts.items():
        c = cost_at(fr, error)
        if c is not None and c < best:
            best, who = c, name
    return {"error": error, "seconds": seconds, "cheapest": who,
            "cheapest_seconds": best, "ratio": seconds / best}


def regime_rows(settings: dict, targets=TARGETS) -> list[list[str]]:
    """The summary table, one row per setting: per target the fastest integrator and the
    runner-up's ratio, then the default's error and ratio (from ``run_setting``'s
    results)."""
    rows = []
    for name, s in settings.items():
        row = [name]
        for e in targets:
            r = s["at"].get(f"{e:.0e}")
            if r is None:
                row.append("below reference" if e not in s["targets"] else "none")
            elif r["runner_up"] is None:
                row.append(f"{r['fastest']} (alone)")
            else:
                row.append(f"{r['fastest']} ({r['runner_up']} {r['runner_up_ratio']:.2g}×)")
        d = s["default"]
        row += [f"{d['error']:.1e}", f"{d['ratio']:.2g}× ({d['cheapest']})"]
        rows.append(row)
    return rows


def _e(x: float | None) -> str:
    return "—" if x is None else f"{x:.1e}"


def markdown(rows: list[list], headers: list[str]) -> str:
    """A Markdown table."""
    out = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


# ---- measuring ---------------------------------------------------------------------------
def run_once(pb, over: dict, ref, e_ref):
    """One run of ``pb.cfg`` with ``over``: (run_time, error, info)."""
    res = rodjit.simulate(pb.cfg.override(over))
    if not np.allclose(res.t, pb.t_eval, rtol=0, atol=1e-12):
        raise RuntimeError("the snapshot times differ from the reference's")
    impact = res.impact()
    e = float(impact["restitution_first"])
    y = np.vstack([res.u.T, res.v.T])
    info = {"steps": int(res.stats["steps"]), "rejected": int(res.stats["rejected_steps"]),
            "restitution": e, "impact_status": impact["impact_status"]}
    err = None
    if ref is not None:
        info["state_error"] = pb.error(y, ref)
        err, info["restitution_error"] = run_error(info["state_error"], e, e_ref)
    return float(res.stats["run_time"]), err, info, y


def measure(pb, over, ref, e_ref, long_run):
    """A rung timed: best of ``REPEATS`` (one run when over ``long_run`` seconds)."""
    t, err, info, _ = run_once(pb, over, ref, e_ref)
    times = [t]
    while len(times) < REPEATS and t <= long_run:
        times.append(run_once(pb, over, ref, e_ref)[0])
    return {"error": err, "times": times, "best": min(times), **info}


def refusal(cfg) -> str | None:
    """Why a run refuses ``cfg`` (its one line), or None."""
    try:
        cfg.check_runnable()
    except (ConfigError, ValueError) as exc:
        return str(exc).splitlines()[0]
    return None


def scan(pb, integrator, ref, e_ref, finest, budget, long_run, quick):
    """One integrator's ladder: ``{"knob", "points", "status"}``."""
    knob, values = ladder(integrator, quick)
    out = {"knob": knob, "points": [], "status": "ok"}
    why = refusal(pb.cfg.override(overrides(integrator, knob, values[0])))
    if why:
        out["status"] = f"refused: {why}"
        return out
    order = registry.get(integrator).order
    probe_over = {**overrides(integrator, knob, values[0]), "time.t_end": PROBE_T}
    try:
        # the probe compiles and warms; only its time is used
        res = rodjit.simulate(pb.cfg.override(probe_over))
        res = rodjit.simulate(pb.cfg.override(probe_over))
        estimate = float(res.stats["run_time"]) * T_END / PROBE_T
    except rodjit.SimulationError as exc:
        out["status"] = f"failed: {str(exc).splitlines()[0][:160]}"
        return out
    done_t, done_v = [], []
    for value in values:
        if done_t:
            estimate = next_estimate(done_t, done_v, knob, order, value)
        if estimate > budget:
            out["points"].append({"value": value, "error": math.inf, "times": [],
                                  "over_budget": estimate})
            break
        try:
            pt = measure(pb, overrides(integrator, knob, value), ref, e_ref, long_run)
        except (rodjit.SimulationError, RuntimeError) as exc:
            out["points"].append({"value": value, "error": math.inf, "times": [],
                                  "failed": str(exc).splitlines()[0][:160]})
            continue
        out["points"].append({"value": value, **pt})
        done_t.append(pt["best"])
        done_v.append(value)
        if pt["error"] < 0.3 * finest:
            break
    return out


def run_setting(name, quick, budget, long_run):
    pb = Problem("paper-mu0", parse_setting(name))
    pb.name = name
    cfg = pb.cfg
    load0 = os.getloadavg()[0]
    _util.header(f"{name}: N = {cfg.rod.N}, μ = {cfg.rod.mu:g}, κ_b = {cfg.floor.kappa_b:g}, "
                 f"β = {cfg.floor.beta:g}, T = {T_END} s")
    t0 = time.perf_counter()
    stiff = cfg.rod.mu * cfg.rod.N ** 2 >= VISCOUS_STIFF
    if stiff:
        _, ref, _ = bench_peers.run_scipy(pb, "Radau", REF_TOL)
        ref_name = f"SciPy Radau rtol=atol={REF_TOL:g} (banded Jacobian)"
    elif bench_peers.available("cyrk"):
        _, ref, _ = bench_peers.run_cyrk(pb, "DOP853", 1e-13)
        ref_name = "CyRK DOP853 rtol=atol=1e-13"
    else:
        _, ref, _ = bench_peers.run_scipy(pb, "DOP853", 1e-13)
        ref_name = "SciPy DOP853 rtol=atol=1e-13"
    t_ref = time.perf_counter() - t0
    ref_integ = "radau5" if stiff else "dop853"
    _, _, info, y = run_once(pb, overrides(ref_integ, "tol", REF_TOL), None, None)
    e_ref = info["restitution"]
    check = pb.error(y, ref)
    print(f"   reference {ref_name} ({t_ref:.1f} s); restitution from rodjit {ref_integ} "
          f"rtol=atol={REF_TOL:g}: e = {e_ref:.10f} ({info['impact_status']}"
          + ("" if math.isfinite(e_ref) else ": the state error alone counts")
          + f"), its state difference {check:.1e} "
          f"({time.perf_counter() - t0:.1f} s in all)")
    targets = [e for e in TARGETS if e >= 10 * check]
    finest = min(targets) if targets else min(TARGETS)
    integrators = {}
    for integ in INTEGRATORS:
        t1 = time.perf_counter()
        integrators[integ] = s = scan(pb, integ, ref, e_ref, finest, budget, long_run, quick)
        s["front"] = front(s["points"])
        ok = [p for p in s["points"] if p["times"]]
        over = [p for p in s["points"] if "over_budget" in p]
        note = s["status"] if s["status"] != "ok" else (
            f"{len(ok)} rungs, finest error "
            f"{min((p['error'] for p in ok), default=math.inf):.1e}"
            + (f", next rung over budget (est. {over[0]['over_budget']:.0f} s)" if over else ""))
        print(f"   {integ:14s} {note} ({time.perf_counter() - t1:.1f} s)", flush=True)
    fronts = {k: s["front"] for k, s in integrators.items() if s["front"]}
    # the default: the preset as a user runs it
    d = measure(pb, {}, ref, e_ref, long_run)
    default = default_ratio(fronts, d["error"], d["best"])
    ran = cfg.resolve()          # what "auto" picked for this setting
    default.update({"integrator": ran.time.integrator, "rtol": ran.time.rtol,
                    "atol": ran.time.atol, "steps": d["steps"], "times": d["times"],
                    "state_error": d["state_error"],
                    "restitution_error": d["restitution_error"]})
    at = {}
    for e in targets:
        at[f"{e:.0e}"] = ratios_at({k: cost_at(fr, e) for k, fr in fronts.items()})
    rows = []
    for integ, s in integrators.items():
        for p in s["points"]:
            if p["times"]:
                rows.append([integ, f"{s['knob']} {p['value']:g}", f"{p['error']:.1e}",
                             f"{p['state_error']:.1e}", _e(p["restitution_error"]),
                             p["steps"], p["rejected"], f"{p['best'] * 1e3:.3g}"])
            else:
                rows.append([integ, f"{s['knob']} {p['value']:g}",
                             "over budget" if "over_budget" in p else p["failed"],
                             "", "", "", "", ""])
        if s["status"] != "ok":
            rows.append([integ, "", s["status"], "", "", "", "", ""])
    rows.append([f"default ({ran.time.integrator})", f"rtol {cfg.time.rtol:g}, atol "
                 f"{cfg.time.atol:g}", f"{d['error']:.1e}", f"{d['state_error']:.1e}",
                 _e(d["restitution_error"]), d["steps"], d["rejected"],
                 f"{d['best'] * 1e3:.3g}"])
    print(markdown(rows, ["integrator", "knob", "error", "state", "restitution", "steps",
                          "rejected", "run ms"]))
    for e in targets:
        r = at[f"{e:.0e}"]
        if r is None:
            print(f"   {e:.0e}: no integrator reaches it")
            continue
        others = ", ".join(f"{k} {v:.2g}×" for k, v in sorted(
            r["ratios"].items(), key=lambda kv: math.inf if kv[1] is None else kv[1])
            if k != r["fastest"] and v is not None)
        print(f"   {e:.0e}: {r['fastest']} {r['seconds'] * 1e3:.3g} ms; {others}")
    print(f"   default: error {default['error']:.1e}, {default['seconds'] * 1e3:.3g} ms, "
          f"{default['ratio']:.2g}× the cheapest there ({default['cheapest']})")
    return {"N": cfg.rod.N, "mu": cfg.rod.mu, "kappa_b": cfg.floor.kappa_b,
            "beta": cfg.floor.beta, "t_end": T_END, "reference": ref_name,
            "restitution_reference": f"rodjit {ref_integ} rtol=atol={REF_TOL:g}",
            "restitution_ref": e_ref, "restitution_ref_status": info["impact_status"],
            "reference_check": check, "targets": targets,
            "integrators": integrators, "at": at, "default": default,
            "load_average_before": load0, "load_average_after": os.getloadavg()[0],
            "wall_seconds": time.perf_counter() - t0}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="N in {5, 20}, kappa_b = 1e3, two rungs: about a minute")
    ap.add_argument("--settings", default=None,
                    help="comma-separated subset, e.g. mu0-N5-kb1e3,mu100-N80-kb1e7")
    ap.add_argument("--budget", type=float, default=20.0,
                    help="seconds: a rung estimated longer is skipped (over budget)")
    ap.add_argument("--long", type=float, default=2.0, dest="long_run",
                    help="seconds: a rung longer than this is timed once, not best of 3")
    ap.add_argument("--out", default=None, help="results/<out>.json (default "
                    "work_precision, or work_precision_quick with --quick)")
    args = ap.parse_args(argv)
    if args.settings:
        names = args.settings.split(",")
        for n in names:
            try:
                parse_setting(n)
            except ValueError as exc:
                ap.error(str(exc))
    else:
        names = setting_names(args.quick)
    warnings.simplefilter("ignore", rodjit.config.ModelWarning)
    t0 = time.perf_counter()
    load0 = os.getloadavg()
    results, path = {}, None
    for n in names:
        results[n] = run_setting(n, args.quick, args.budget, args.long_run)
        path = _util.save(args.out or ("work_precision_quick" if args.quick
                                       else "work_precision"),
                          {"quick": args.quick, "budget_seconds": args.budget,
                           "targets": list(TARGETS), "complete": len(results) == len(names),
                           "load_average_start": list(load0),
                           "load_average_end": list(os.getloadavg()),
                           "wall_seconds": time.perf_counter() - t0, "settings": results})
    print("\nfastest integrator per setting and target (runner-up and its cost ratio); the "
          "default (the preset: auto, rtol 1e-6, atol 1e-9), its error and its cost over "
          "the cheapest at that error:\n")
    print(markdown(regime_rows(results), ["setting"] + [f"{e:.0e}" for e in TARGETS]
                   + ["default error", "default / cheapest"]))
    la = os.getloadavg()
    print(f"\n{time.perf_counter() - t0:.0f} s wall; load average at start "
          f"{load0[0]:.2f}/{load0[1]:.2f}/{load0[2]:.2f}, at end {la[0]:.2f}/{la[1]:.2f}/"
          f"{la[2]:.2f}")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
