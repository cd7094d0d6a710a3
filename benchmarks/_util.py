"""Shared helpers of the benchmark scripts: timing, tables, JSON results, the C anchor."""
from __future__ import annotations

import datetime
import hashlib
import json
import os
import platform
import shutil
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RESULTS = HERE / "results"

# The speed-limit anchor: ../shared/bench/limit.c next to the repository when present (the
# project's reference copy), else the vendored copy benchmarks/limit.c.
LIMIT_C_CANDIDATES = [ROOT.parent / "shared" / "bench" / "limit.c", HERE / "limit.c"]


def _version(mod: str) -> str | None:
    try:
        return __import__(mod).__version__
    except Exception:
        return None


def _git(*args: str) -> str | None:
    try:
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True,
                              check=True).stdout.strip()
    except Exception:
        return None


def _rodjit_path() -> str | None:
    mod = sys.modules.get("rodjit")
    return str(Path(mod.__file__).parent) if mod is not None else None


def _cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine() -> dict:
    """Where and with what the numbers were measured."""
    return {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "cpu": _cpu(),
        "cores": os.cpu_count(),
        "load_average_1min": os.getloadavg()[0] if hasattr(os, "getloadavg") else None,
        "python": platform.python_version(),
        "numpy": _version("numpy"),
        "numba": _version("numba"),
        "scipy": _version("scipy"),
        "rodjit_module": _rodjit_path(),
        "rodjit_commit": _git("rev-parse", "HEAD"),
        # what the measured code is made of (not the results and logs the run rewrites,
        # nor the documentation)
        "rodjit_dirty": bool(_git("status", "--porcelain", "--untracked-files=no", "--",
                                  "rodjit", "benchmarks/*.py", "benchmarks/*.c",
                                  "pyproject.toml")),
    }


def save(name: str, payload: dict) -> Path:
    """Write ``benchmarks/results/<name>.json`` (with the machine description)."""
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"{name}.json"
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps({"benchmark": name, "machine": machine(), **payload},
                              indent=2, default=float) + "\n")
    os.replace(tmp, path)
    return path


def table(rows: list[list], headers: list[str]) -> str:
    """A plain-text table; floats get 4 significant digits."""
    def fmt(x):
        if isinstance(x, float):
            return f"{x:.4g}"
        return str(x)
    cells = [[fmt(x) for x in r] for r in rows]
    widths = [max(len(h), *(len(r[i]) for r in cells)) for i, h in enumerate(headers)]
    line = "  ".join(h.ljust(w) for h, w in zip(headers, widths))
    out = [line, "  ".join("-" * w for w in widths)]
    out += ["  ".join(c.ljust(w) for c, w in zip(r, widths)) for r in cells]
    return "\n".join(out)


def best(times: list[float]) -> float:
    """Best of repeated timings: the least disturbed by other load on the machine."""
    return min(times)


# ---- the C anchor ---------------------------------------------------------------------
def limit_source() -> Path:
    for p in LIMIT_C_CANDIDATES:
        if p.is_file():
            return p
    raise FileNotFoundError("limit.c not found in " + ", ".join(map(str, LIMIT_C_CANDIDATES)))


def build_limit(workdir: Path) -> dict:
    """Compile limit.c with ``gcc -O3 -march=native``; returns path, source, flags."""
    src = limit_source()
    cc = os.environ.get("CC", "gcc")
    if shutil.which(cc) is None:
        raise RuntimeError(f"C compiler {cc!r} not found (set CC)")
    exe = Path(workdir) / "limit"
    flags = ["-O3", "-march=native"]
    subprocess.run([cc, *flags, "-o", str(exe), str(src), "-lm"], check=True)
    version = subprocess.run([cc, "--version"], capture_output=True, text=True).stdout
    return {"exe": str(exe), "source": str(src),
            "source_sha1": hashlib.sha1(src.read_bytes()).hexdigest(),
            "compiler": version.splitlines()[0] if version else cc, "flags": " ".join(flags)}


def run_limit(exe: str, n: int, steps: int, gamma: float | None = None) -> dict:
    """One run of the C loop; returns its printed fields (ns_per_node_step, dt, ...)."""
    args = [exe, str(n), str(steps)] + ([repr(gamma)] if gamma is not None else [])
    out = subprocess.run(args, capture_output=True, text=True, check=True).stdout
    fields = dict(kv.split("=") for kv in out.split())
    return {k: float(v) for k, v in fields.items()}


def timed(fn):
    t0 = time.perf_counter()
    value = fn()
    return time.perf_counter() - t0, value


def header(title: str) -> None:
    print(f"\n== {title} ==")
    m = machine()
    print(f"   {m['cpu']} ({m['cores']} cores, load {m['load_average_1min']:.2f}), "
          f"Python {m['python']}, NumPy {m['numpy']}, Numba {m['numba']}, "
          f"commit {str(m['rodjit_commit'])[:10]}{' (dirty)' if m['rodjit_dirty'] else ''}")
    sys.stdout.flush()
