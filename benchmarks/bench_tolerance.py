"""What a tolerance buys: the first restitution's error and the delivered state error of
each integrator under tolerance control, against dop853 at rtol 1e-12, with its steps and
time.

    python benchmarks/bench_tolerance.py [--no-docs]

Six integrators × tol ∈ {1e-3, 1e-5, 1e-7} (rtol = tol, atol = 1e-3·tol), paper-mu0 and
paper-mu100.  Two measurements per cell:

* the first restitution at T = 2 (no snapshots): the error of ``rodjit.observables``'s
  ``restitution_first``, with the accepted steps and the wall time; a cell above 10 × tol
  is marked ``!``;
* the state over the first second (T = 1, the preset's snapshots): the largest error of
  the snapshot heights (m) and of the snapshot velocities divided by the impact speed
  √(v₀² + 2|g|·height), against dop853 at rtol 1e-12, atol 1e-15 with the same snapshots,
  with the accepted steps.  Below each preset's state table, per tolerance, the spread of
  the integrators' errors (the largest over the smallest of max(heights, velocities)).

An integrator that refuses the tolerance (``Config.check_runnable``) is ``refused``.
Writes benchmarks/results/tolerance.json and the tables between the markers of
docs/integrators.md.
"""
import json
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import rodjit
from rodjit.presets import load_preset

INTEGRATORS = ("verlet", "semi-implicit", "energy", "dp54", "dop853", "radau5")
TOLS = (1e-3, 1e-5, 1e-7)
PRESETS = ("paper-mu0", "paper-mu100")
ROOT = Path(__file__).resolve().parent.parent
BEGIN, END = "<!-- bench_tolerance: begin -->", "<!-- bench_tolerance: end -->"


def _config(preset, integrator, rtol, atol):
    return load_preset(preset).override({
        "time.t_end": 2.0, "time.integrator": integrator, "time.control": "tolerance",
        "time.rtol": rtol, "time.atol": atol, "output.snapshot_interval": 0.0})


def _restitution(cfg):
    t0 = time.perf_counter()
    res = rodjit.simulate(cfg)
    wall = time.perf_counter() - t0
    return rodjit.observables(res)["restitution_first"], res.stats["steps"], wall


def _state_config(preset, integrator, rtol, atol):
    return _config(preset, integrator, rtol, atol).override({
        "time.t_end": 1.0,
        "output.snapshot_interval": load_preset(preset).output.snapshot_interval})


def _impact_speed(cfg):
    return math.sqrt(cfg.initial.velocity ** 2 + 2.0 * abs(cfg.gravity.g) * cfg.initial.height)


def _state(cfg, ref):
    """(heights error m, velocities error / impact speed, accepted steps) over the
    snapshots of the first second against ``ref``'s."""
    res = rodjit.simulate(cfg)
    if not np.array_equal(res.t, ref.t):
        raise RuntimeError(f"{cfg.time.integrator}: snapshot times differ from the reference")
    return (float(np.abs(res.u - ref.u).max()),
            float(np.abs(res.v - ref.v).max() / _impact_speed(cfg)), res.stats["steps"])


def measure():
    rows = []
    for preset in PRESETS:
        ref, _, _ = _restitution(_config(preset, "dop853", 1e-12, 1e-15))
        ref_state = rodjit.simulate(_state_config(preset, "dop853", 1e-12, 1e-15))
        for integrator in INTEGRATORS:
            for tol in TOLS:
                cfg = _config(preset, integrator, tol, 1e-3 * tol)
                try:
                    cfg.check_runnable()
                except ValueError:
                    rows.append(dict(preset=preset, integrator=integrator, tol=tol,
                                     refused=True))
                    continue
                _restitution(cfg)                      # compiled and warm
                e, steps, wall = _restitution(cfg)
                err = abs(e - ref)
                du, dv, state_steps = _state(_state_config(preset, integrator, tol, 1e-3 * tol),
                                             ref_state)
                rows.append(dict(preset=preset, integrator=integrator, tol=tol, refused=False,
                                 restitution=e, reference=ref, error=err, steps=steps,
                                 seconds=wall, over=err > 10 * tol, state_heights=du,
                                 state_velocities=dv, state_steps=state_steps))
                print(f"{preset} {integrator:13s} {tol:.0e} err {err:.2g} steps {steps} "
                      f"{wall:.3f} s; state: heights {du:.2g} velocities {dv:.2g} "
                      f"steps {state_steps}", flush=True)
    return rows


def _row(rows, preset, integrator, tol):
    return next(r for r in rows if (r["preset"], r["integrator"], r["tol"]) ==
                (preset, integrator, tol))


def spread(rows, preset, tol) -> float:
    """The largest over the smallest of the integrators' state errors max(heights,
    velocities) at one tolerance."""
    errs = [max(r["state_heights"], r["state_velocities"]) for r in rows
            if (r["preset"], r["tol"]) == (preset, tol) and not r["refused"]]
    return max(errs) / min(errs)


def _grid(rows, preset: str, title: str, cell) -> list[str]:
    """One preset's Markdown table, integrators × TOLS, ``cell(row)`` in each cell."""
    lines = [title, "", "| integrator | " + " | ".join(f"tol {t:.0e}" for t in TOLS) + " |",
             "|---|" + "---|" * len(TOLS)]
    for integrator in INTEGRATORS:
        cells = [_row(rows, preset, integrator, tol) for tol in TOLS]
        lines.append(f"| `{integrator}` | " + " | ".join(
            "refused" if r["refused"] else cell(r) for r in cells) + " |")
    return lines


def state_table(rows) -> list[str]:
    lines = []
    for preset in PRESETS:
        lines += _grid(rows, preset,
                       f"`{preset}`, t ≤ 1 s: largest snapshot error of the heights (m) / of "
                       f"the velocities ÷ the impact speed against dop853 at rtol 1e-12 / "
                       f"accepted steps",
                       lambda r: f"{r['state_heights']:.1e} / {r['state_velocities']:.1e} / "
                                 f"{r['state_steps']:,}")
        lines.append("| spread (largest ÷ smallest) | " + " | ".join(
            f"{spread(rows, preset, tol):.3g}×" for tol in TOLS) + " |")
        lines.append("")
    return lines


def table(rows) -> str:
    lines = []
    for preset in PRESETS:
        lines += _grid(rows, preset,
                       f"`{preset}`, T = 2 s: first-restitution error against dop853 at rtol "
                       f"1e-12 / accepted steps / wall time",
                       lambda r: f"{r['error']:.1e}{' !' if r['over'] else ''} / "
                                 f"{r['steps']:,} / {r['seconds'] * 1e3:.3g} ms")
        lines.append("")
    lines += state_table(rows)
    lines.append("`!`: above 10 × tol.  `refused`: the integrator refuses the tolerance "
                 "there (`verlet` above `rod.mu = 1`).  Remade by "
                 "`python benchmarks/bench_tolerance.py`.")
    return "\n".join(lines)


def main():
    from rodjit.config import ModelWarning
    warnings.simplefilter("ignore", ModelWarning)
    rows = measure()
    out = ROOT / "benchmarks" / "results" / "tolerance.json"
    out.write_text(json.dumps(rows, indent=1))
    text = table(rows)
    print(text)
    over = [r for r in rows if not r["refused"] and r["over"]]
    print(f"{len(over)} cells above 10 x tol: " + ", ".join(
        f"{r['preset']} {r['integrator']} {r['tol']:.0e} ({r['error']:.2g})" for r in over))
    if "--no-docs" not in sys.argv:
        doc = ROOT / "docs" / "integrators.md"
        s = doc.read_text()
        if BEGIN in s and END in s:
            head, rest = s.split(BEGIN, 1)
            s = head + BEGIN + "\n" + text + "\n" + END + rest.split(END, 1)[1]
        else:
            s += f"\n## What a tolerance buys\n\n{BEGIN}\n{text}\n{END}\n"
        doc.write_text(s)


if __name__ == "__main__":
    main()
