"""Write the golden outputs that ``tests/test_golden.py`` compares against, bit for bit.

The goldens pin what a refactoring must not change: one run file per integrator, μ = 0 and
μ > 0, γ > 0, a run interrupted and resumed, and a small sweep.  Every case states its whole
configuration (integrator, step control, outputs), so changing a *default* leaves them valid;
a change that is meant to alter results regenerates them with

    python tests/golden/make_golden.py

and says so in CHANGELOG.md.

Each golden records the machine that wrote it (``machine()``: the CPU as LLVM sees it).
The kernels may fuse multiplies and adds (``rodjit._jit``), and where LLVM fuses depends
on the CPU it compiles for: two CPUs with FMA (an Intel Xeon and an AMD EPYC, say) give
the same run to rounding, not to the bit.  So a golden is compared bit for bit on a
machine like the one that wrote it, and to the rounding that CPUs can differ by elsewhere
(``tests/test_golden.py``).
"""
from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import h5py
import numpy as np

import rodjit

HERE = Path(__file__).resolve().parent

_COMMON = {"time.t_end": 1.0, "time.dt": None, "time.dt_max": None, "time.dt_min": 1e-12,
           "output.snapshot_interval": 0.01, "output.diagnostics_interval": 0.002,
           "output.compression": "none"}

# name -> overrides; rtol/atol set the steps of energy, dp54, dop853 and radau5, cfl
# (time.control = "cfl") those of verlet and semi-implicit
CASES: dict[str, dict] = {
    "verlet_mu0": {"time.integrator": "verlet", "time.cfl": 0.05, "time.control": "cfl"},
    "verlet_mu10_gamma": {"time.integrator": "verlet", "time.cfl": 0.05, "time.control": "cfl", "rod.mu": 10.0,
                          "rod.gamma": 1e-4, "rod.N": 12},
    "semi_implicit_mu100": {"time.integrator": "semi-implicit", "time.cfl": 0.05, "time.control": "cfl",
                            "rod.mu": 100.0},
    "semi_implicit_gamma": {"time.integrator": "semi-implicit", "time.cfl": 0.05, "time.control": "cfl",
                            "rod.gamma": 1e-3, "rod.N": 16, "rod.mu": 1.0},
    "energy_mu0": {"time.integrator": "energy", "time.rtol": 1e-6, "time.atol": 1e-9},
    "energy_mu100_gamma": {"time.integrator": "energy", "time.rtol": 1e-5,
                           "time.atol": 1e-8, "rod.mu": 100.0, "rod.gamma": 1e-4,
                           "rod.N": 10},
    "verlet_fixed_dt": {"time.integrator": "verlet", "time.dt": 2e-4, "time.control": "cfl"},
    "dp54_mu0": {"time.integrator": "dp54", "time.control": "tolerance", "time.rtol": 1e-6,
                 "time.atol": 1e-9},
    "dop853_mu1": {"time.integrator": "dop853", "time.control": "tolerance", "time.rtol": 1e-7,
                   "time.atol": 1e-10, "rod.mu": 1.0},
    "radau5_mu100": {"time.integrator": "radau5", "time.control": "tolerance",
                     "time.rtol": 1e-5, "time.atol": 1e-8, "rod.mu": 100.0, "rod.N": 10},
}
RESUMED = ("energy_mu0", "semi_implicit_mu100")   # also written in two sessions
SWEEP_GRID = {"rod.mu": [0.0, 10.0], "floor.kappa_b": [1000.0, 3000.0]}
SWEEP_BASE = {"time.integrator": "verlet", "time.cfl": 0.05, "time.control": "cfl", "time.t_end": 0.8}


def config(name: str) -> rodjit.Config:
    return rodjit.Config().override(_COMMON | CASES[name])


def machine() -> str:
    """The CPU that Numba compiles for (LLVM's name of the host and its features): what
    decides whether two machines give the same kernels' results to the bit."""
    import llvmlite.binding as ll

    return f"{ll.get_host_cpu_name()} {ll.get_host_cpu_features().flatten()}"


def write_run(name: str, path: Path) -> None:
    rodjit.run_to_file(config(name), path, overwrite=True, handle_signals=False)


def write_resumed(name: str, path: Path) -> None:
    """The same run written in two sessions: to t = 0.4, then resumed to t_end."""
    cfg = config(name)
    rodjit.run_to_file(cfg, path, overwrite=True, t_end=0.4, handle_signals=False)
    rodjit.resume_file(path, t_end=cfg.time.t_end, handle_signals=False)


def write_sweep(path: Path) -> None:
    base = rodjit.Config().override(_COMMON | SWEEP_BASE)
    rodjit.sweep(base, SWEEP_GRID, output=path, jobs=1, scheduler="inline", overwrite=True,
                 handle_signals=False)


# what differs between two runs of the same code: timings, the writer, the clock of the day
VOLATILE = ("compile_time", "run_time", "wall_time", "row_digest")   # a digest of them too
KEPT_ATTRS = ("rodjit_kind", "format_version", "status", "message", "n_points", "grid",
              "grid_keys")


def _plain(value) -> np.ndarray:
    """An array without h5py's dtype metadata (vlen strings become str, bool stays bool),
    which .npz cannot store."""
    data = np.asarray(value.decode() if isinstance(value, bytes) else value)
    if data.dtype.kind in "OSU":
        return np.array([x.decode() if isinstance(x, bytes) else str(x)
                         for x in data.ravel()]).reshape(data.shape)
    return np.asarray(data, dtype=np.dtype(data.dtype.str))


def extract(path: Path) -> dict[str, np.ndarray]:
    """What a golden pins of a file: every dataset (timings excepted), the valid checkpoint's
    stepper arrays under ``checkpoint:``, the stable root attributes under ``attr:``, and the
    stored configuration as JSON under ``config`` (compared key by key, so new keys may be
    added without invalidating a golden)."""
    out: dict[str, np.ndarray] = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if not isinstance(obj, h5py.Dataset) or name.startswith("checkpoint"):
                return
            if name.rsplit("/", 1)[-1] in VOLATILE:
                return
            out[name] = _plain(obj[()])
        f.visititems(visit)
        if "checkpoint" in f:
            slot = f["checkpoint"][f"slot{int(f['checkpoint/current'][()])}"]
            for key in ("state", "clock", "count", "ev", "sstats", "lengths"):
                out[f"checkpoint:{key}"] = slot[key][()]
        for key in KEPT_ATTRS:
            if key in f.attrs:
                out[f"attr:{key}"] = _plain(f.attrs[key])
        toml = f.attrs.get("config_toml", f.attrs.get("base_config_toml"))
        if toml is not None:
            flat = rodjit.Config.from_toml_string(str(toml)).flat()
            out["config"] = np.array(json.dumps(flat, sort_keys=True))
    return out


def write_all(folder: Path) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for name in CASES:
        write_run(name, folder / f"{name}.h5")
        written.append(folder / f"{name}.h5")
    for name in RESUMED:
        write_resumed(name, folder / f"{name}_resumed.h5")
        written.append(folder / f"{name}_resumed.h5")
    write_sweep(folder / "sweep.h5")
    written.append(folder / "sweep.h5")
    return written


def main(folder: Path, names: list[str] | None = None) -> None:
    """Write every golden into ``folder``, or only the run files of ``names`` (cases)."""
    with tempfile.TemporaryDirectory() as tmp:
        paths = write_all(Path(tmp)) if not names else []
        for name in names or ():
            write_run(name, Path(tmp) / f"{name}.h5")
            paths.append(Path(tmp) / f"{name}.h5")
        for path in paths:
            target = folder / (path.stem + ".npz")
            np.savez_compressed(target, **extract(path), machine=np.array(machine()))
            print(target)


if __name__ == "__main__":
    # python tests/golden/make_golden.py [FOLDER [CASE ...]]
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE, sys.argv[2:])
