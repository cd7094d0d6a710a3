"""The GPU engine's refusals: one line, exit code 2 from the command line, nothing written.

Run without the simulator: the checks come before any kernel (numba-cuda missing, no GPU,
N above the limit, an integrator or a law without a GPU version, run files)."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from rodjit.config import Config
from rodjit.gpu import engine
from rodjit.gpu._cuda import CudaUnavailable
from rodjit.laws import Law

ROOT = Path(__file__).resolve().parent.parent


def _cuda_or_skip():
    from rodjit.gpu._cuda import import_cuda

    try:
        import_cuda()
    except CudaUnavailable as exc:
        pytest.skip(str(exc))


def _gpu_present() -> bool:
    if os.environ.get("NUMBA_ENABLE_CUDASIM") == "1":
        return True
    try:
        engine.check_device()
    except CudaUnavailable:
        return False
    return True


def test_numba_cuda_missing_names_the_extra(tmp_path):
    out = tmp_path / "s.h5"
    code = ("import sys; sys.modules['numba_cuda'] = sys.modules['numba.cuda'] = None\n"
            "from rodjit.entry import main\n"
            f"sys.argv = ['rodjit', 'sweep', '--device', 'cuda', '--grid', "
            f"'rod.mu=0,1', '-o', {str(out)!r}]\n"
            "main()\n")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    env.pop("NUMBA_ENABLE_CUDASIM", None)
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                       timeout=300)
    assert p.returncode == 2, p.stderr
    err = p.stderr.strip().splitlines()
    assert len(err) == 1 and "rodjit[cuda]" in err[0] and "numba-cuda" in err[0], p.stderr
    assert not out.exists()


def test_no_gpu_is_one_line(tmp_path):
    _cuda_or_skip()
    if _gpu_present():
        pytest.skip("a GPU (or the simulator) is here")
    from rodjit.cli import main

    out = tmp_path / "s.h5"
    r = CliRunner().invoke(main, ["sweep", "--device", "cuda", "--grid", "rod.mu=0,1", "-o",
                                  str(out)])
    assert r.exit_code == 2
    lines = [x for x in r.output.strip().splitlines() if x]
    assert "no CUDA GPU" in lines[-1] and "device = 'cpu'" in lines[-1]
    assert not out.exists()


def test_auto_is_the_cpu_without_a_gpu():
    _cuda_or_skip()
    if _gpu_present():
        pytest.skip("a GPU (or the simulator) is here")
    assert engine.resolve_device("auto") == "cpu"
    assert engine.resolve_device(None) == "cpu"
    with pytest.raises(ValueError, match="not one of 'cpu', 'cuda', 'auto'"):
        engine.resolve_device("gpu")


def test_rod_above_the_limit():
    with pytest.raises(engine.GpuUnsupported, match=r"rod.N = 65 is out of range .*1 to 64"):
        engine.check_point(Config().override({"rod.N": 65}))
    engine.check_point(Config().override({"rod.N": 64}))


def test_integrator_without_gpu_version(monkeypatch):
    monkeypatch.setattr(engine, "GPU_INTEGRATORS", ("energy",))
    with pytest.raises(engine.GpuUnsupported,
                       match=r"time.integrator = 'dp54' has no GPU version"):
        engine.check_point(Config().override({"time.integrator": "dp54"}))


def test_law_without_gpu_version(monkeypatch):
    """A law whose functions are not rodjit kernels (here plain Python) cannot be compiled
    for the GPU: refused in one line naming it."""
    real = engine.get_law

    def plain(kind, name):
        law = real(kind, name)
        if kind != "floor":
            return law
        return Law(name=name, kind=kind, params=law.params, from_config=law.from_config,
                   value=lambda h, p: 0.0, deriv=law.deriv, primitive=law.primitive,
                   lower=law.lower)

    monkeypatch.setattr(engine, "get_law", plain)
    with pytest.raises(engine.GpuUnsupported,
                       match=r"floor.law = 'aiki-kosugi' has no GPU version"):
        engine.check_point(Config())

