"""The fixed cost of one ``rodjit.simulate`` call: where a warm call's time goes outside
the compiled loop.

    python benchmarks/bench_fixed_cost.py [--repeat 300] [--out fixed_cost]

Each case is one Config run warm (compiled first), ``--repeat`` times.  The call is taken
apart into the steps ``driver.simulate.simulate`` takes, timed with ``perf_counter`` one
after the other in the same order:

  checks     the argument check and ``check_fixed_step``
  setup      ``Run(config)``: validation, the parameter tuples, the initial state, the
             arrays, the compiled entry's key
  warn       ``warn_config`` (the configuration's warnings; filtered out here)
  start      ``Run.start``: the compiled evaluation of the initial state
  loop       the compiled loop itself (``stats['run_time']``)
  glue       the rest of ``Run.advance``: argument tuples, ``take``, ``drain`` (copies
             into the sink)
  result     ``MemorySink.result``: the Result, its columns, bounce table and stats

``config`` (building the Config from the preset and overrides, not part of the call) is
printed apart.  Every part is the median over the repeats, printed in µs (saved in ms),
with its share of the whole call (the sum of the parts); ``simulate`` is the median of
whole ``rodjit.simulate`` calls timed alone, interleaved with the split ones, to check
that the split adds up.

Cases: the bench_peers settings (paper μ = 0 and μ = 100, T = 1 s, snapshots and
diagnostics every 5 ms) with the integrators that are rodjit's best there (μ = 0:
``dop853`` at rtol = atol = 1e-6 and ``dp54`` at 1e-4; μ = 100: ``radau5`` at 1e-6 and
1e-3), and a tiny run (t_end = 1 ms) where the fixed cost is nearly all of the call.
The ``new-config/`` cases make a new Config for every call, as ``bench_peers.py`` does
(``override`` of the setting's Config with the integrator and tolerance, outside the
timed call); both find the pieces of their set-up kept by the values of what each reads
(``driver.setup``).
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _util  # noqa: E402

import rodjit  # noqa: E402
from rodjit.driver.run import Run, warn_config  # noqa: E402
from rodjit.output.estimate import check_fixed_step  # noqa: E402
from rodjit.presets import load_preset  # noqa: E402
from rodjit.records.result import MemorySink  # noqa: E402
from rodjit.stepping import layout as L  # noqa: E402

PEERS = {"time.t_end": 1.0, "output.snapshot_interval": 0.005,
         "output.diagnostics_interval": 0.005}
CASES = {
    "paper-mu0/dop853/1e-6": ("paper-mu0", {**PEERS, "time.integrator": "dop853",
                                            "time.rtol": 1e-6, "time.atol": 1e-6}),
    "paper-mu0/dp54/1e-4": ("paper-mu0", {**PEERS, "time.integrator": "dp54",
                                          "time.rtol": 1e-4, "time.atol": 1e-4}),
    "paper-mu100/radau5/1e-6": ("paper-mu100", {**PEERS, "time.integrator": "radau5",
                                                "time.rtol": 1e-6, "time.atol": 1e-6}),
    "paper-mu100/radau5/1e-3": ("paper-mu100", {**PEERS, "time.integrator": "radau5",
                                                "time.rtol": 1e-3, "time.atol": 1e-3}),
    "tiny/paper-mu0/energy/t_end=1ms": ("paper-mu0", {"time.t_end": 1e-3}),
}
# bench_peers' pattern: every call gets a new Config, ``override`` of the setting's one
# with its integrator and tolerance (built outside the timed call)
NEW_CONFIG = {
    "new-config/paper-mu0/dop853/1e-6": ("paper-mu0/dop853/1e-6", ("time.integrator",
                                                                   "time.rtol", "time.atol")),
    "new-config/paper-mu100/radau5/1e-3": ("paper-mu100/radau5/1e-3", ("time.integrator",
                                                                       "time.rtol",
                                                                       "time.atol")),
}
PARTS = ("checks", "setup", "warn", "start", "loop", "glue", "result")


def _sink() -> MemorySink:
    """The sink ``simulate`` uses: one that keeps the run's last block uncopied where this
    version of rodjit has it (so that the script also measures versions before it)."""
    try:
        return MemorySink(views=True)
    except TypeError:
        sink = MemorySink()
        sink.settle = lambda: None
        return sink


def split_call(cfg) -> dict:
    """One ``simulate`` call taken apart (module docstring); seconds per part."""
    clock = time.perf_counter
    t0 = clock()
    if not isinstance(cfg, rodjit.Config):
        raise TypeError
    check_fixed_step(cfg, max_steps=float("inf"))
    t1 = clock()
    run = Run(cfg)
    t2 = clock()
    warn_config(cfg)
    sink = _sink()
    t3 = clock()
    run.start(None)
    t4 = clock()
    while run.advance(sink) != L.DONE:
        sink.settle()
    t5 = clock()
    res = sink.result(run)
    t6 = clock()
    loop = run.run_time
    assert res.status == "completed"
    return {"checks": t1 - t0, "setup": t2 - t1, "warn": t3 - t2, "start": t4 - t3,
            "loop": loop, "glue": t5 - t4 - loop, "result": t6 - t5}


def measure(preset: str, over: dict, repeat: int, new_keys: tuple = ()) -> dict:
    """The parts of ``repeat`` calls of one Config; with ``new_keys``, of a new Config
    for every call (``override`` of the same one with ``new_keys`` of ``over``)."""
    t0 = time.perf_counter()
    cfg = load_preset(preset).override(over)
    config_s = time.perf_counter() - t0
    base = load_preset(preset).override({k: v for k, v in over.items() if k not in new_keys})
    again = {k: over[k] for k in new_keys}

    def config():
        return base.override(again) if new_keys else cfg

    for _ in range(3):
        rodjit.simulate(config())               # compile, warm caches
    parts = {p: [] for p in PARTS}
    whole = []
    for _ in range(repeat):
        for p, s in split_call(config()).items():
            parts[p].append(s)
        c = config()
        t0 = time.perf_counter()
        rodjit.simulate(c)
        whole.append(time.perf_counter() - t0)
    med = {p: statistics.median(v) for p, v in parts.items()}
    return {"config_ms": 1e3 * config_s, "parts_ms": {p: 1e3 * s for p, s in med.items()},
            "sum_ms": 1e3 * sum(med.values()), "simulate_ms": 1e3 * statistics.median(whole),
            "simulate_best_ms": 1e3 * min(whole),
            "outside_loop_ms": 1e3 * (sum(med.values()) - med["loop"])}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=300)
    ap.add_argument("--cases", default=None, help="comma-separated subset of case names")
    ap.add_argument("--out", default="fixed_cost")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore", rodjit.config.ModelWarning)
    names = list(CASES) + list(NEW_CONFIG) if args.cases is None else args.cases.split(",")
    results = {}
    for name in names:
        case, new_keys = NEW_CONFIG.get(name, (name, ()))
        preset, over = CASES[case]
        r = results[name] = measure(preset, over, args.repeat, new_keys)
        total = r["sum_ms"]
        rows = [[p, r["parts_ms"][p] * 1e3, 100 * r["parts_ms"][p] / total] for p in PARTS]
        rows.append(["outside the loop", r["outside_loop_ms"] * 1e3,
                     100 * r["outside_loop_ms"] / total])
        rows.append(["sum of parts", total * 1e3, 100.0])
        rows.append(["simulate (median, whole)", r["simulate_ms"] * 1e3,
                     100 * r["simulate_ms"] / total])
        print(f"== {name} (config built in {r['config_ms']:.3f} ms, apart) ==")
        print(_util.table(rows, ["part", "µs", "% of call"]))
        print()
    path = _util.save(args.out, {"repeat": args.repeat, "cases": results})
    print(f"saved {path}")


if __name__ == "__main__":
    main()
