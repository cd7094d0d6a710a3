"""The symmetric tridiagonal solver (variable off-diagonal) used by the energy step, and the
second solve with its stored factor (the chord updates of Newton's method)."""
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rodjit.kernels.banded import sym_tridiag_apply, sym_tridiag_solve


@pytest.mark.parametrize("n1", [1, 2, 3, 6, 7, 17, 400])
def test_solves_spd_tridiagonal_systems(n1):
    rng = np.random.default_rng(n1)
    e = rng.uniform(-1.0, 1.0, n1)           # e[i] couples i and i+1 (last entry unused)
    d = np.abs(e) + np.abs(np.roll(e, 1)) + rng.uniform(1e-3, 2.0, n1)   # SPD by dominance
    d[0] = abs(e[0]) + 0.5
    A = np.diag(d) + np.diag(e[:-1], 1) + np.diag(e[:-1], -1)
    b = rng.standard_normal(n1)
    cp, pinv, x = np.zeros(n1), np.zeros(n1), np.zeros(n1)
    sym_tridiag_solve(d, e, b, x, cp, pinv)
    np.testing.assert_allclose(A @ x, b, rtol=0, atol=1e-12 * np.abs(b).max())
    y = b.copy()
    sym_tridiag_solve(d, e, y, y, np.zeros(n1), np.zeros(n1))   # in place
    np.testing.assert_array_equal(y, x)
    # the stored factor solves other right-hand sides, and the first one to the same bits
    c = rng.standard_normal(n1)
    z = np.zeros(n1)
    sym_tridiag_apply(e, cp, pinv, c, z)
    np.testing.assert_allclose(A @ z, c, rtol=0, atol=1e-12 * np.abs(c).max())
    sym_tridiag_apply(e, cp, pinv, c, c)       # in place
    np.testing.assert_array_equal(c, z)
    sym_tridiag_apply(e, cp, pinv, b, z)
    np.testing.assert_array_equal(z, x)


def _stiff_system():
    """A Newton matrix that mixes masses ~1e-3 with stiffnesses ~1e8 (contact rows):
    diagonal, off-diagonal, right-hand side."""
    n1 = 200
    h = 1.0 / (n1 - 1)
    d = np.full(n1, h)
    d[0] = d[-1] = h / 2
    c = np.full(n1, 1e3)
    c[0] = 1e8
    e = -c.copy()
    dd = d.copy()
    dd[:-1] += c[:-1]
    dd[1:] += c[:-1]
    return dd, e, np.linspace(-1, 1, n1)


def test_stiff_and_mass_scaled_rows():
    """Its pivots cancel to O(mass) out of O(stiffness): elimination must keep them accurate
    (fused multiply-adds in the pivots would lose 4 digits here)."""
    d, e, b = _stiff_system()
    A = np.diag(d) + np.diag(e[:-1], 1) + np.diag(e[:-1], -1)
    cp, pinv, x = np.zeros(b.size), np.zeros(b.size), np.zeros(b.size)
    sym_tridiag_solve(d, e, b, x, cp, pinv)
    ref = np.linalg.solve(A, b)
    np.testing.assert_allclose(x, ref, rtol=1e-8)
    sym_tridiag_apply(e, cp, pinv, b, x)
    np.testing.assert_allclose(x, ref, rtol=1e-8)


FUSED_CALLER = """
import sys
import numpy as np
from rodjit._jit import kernel
from rodjit.kernels.banded import sym_tridiag_solve
sys.path.insert(0, {tests!r})
from test_kernels_banded_symmetric import _stiff_system


@kernel
def solve_inside(d, e, b, x, cp, pinv):
    sym_tridiag_solve(d, e, b, x, cp, pinv)


d, e, b = _stiff_system()
x = np.zeros(b.size)
solve_inside(d, e, b, x, np.zeros(b.size), np.zeros(b.size))   # compiles it as a callee, first
A = np.diag(d) + np.diag(e[:-1], 1) + np.diag(e[:-1], -1)
ref = np.linalg.solve(A, b)
print(np.abs(x - ref).max() / np.abs(ref).max())
"""


def test_solver_stays_unfused_inside_a_fused_kernel(tmp_path):
    """Numba compiles a callee with its caller's fast-math flags unless it sets its own
    (and caches it so): the solver's pivots must stay unfused (rodjit._jit) when a fused
    kernel, as the energy step, compiles it first.  A fresh process and cache, so the
    solver is compiled there first."""
    script = tmp_path / "fused_caller.py"
    script.write_text(FUSED_CALLER.format(tests=str(Path(__file__).resolve().parent)))
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    out = subprocess.run([sys.executable, str(script)], env=env, capture_output=True,
                         text=True, check=True, timeout=300)
    assert float(out.stdout.split()[-1]) < 1e-10
