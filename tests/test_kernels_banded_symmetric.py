"""The symmetric tridiagonal LDLᵀ solver (variable off-diagonal) used by the energy step."""
import numpy as np
import pytest

from rodjit.kernels.banded import sym_tridiag_solve


@pytest.mark.parametrize("n1", [1, 2, 3, 6, 7, 17, 400])
def test_solves_spd_tridiagonal_systems(n1):
    rng = np.random.default_rng(n1)
    e = rng.uniform(-1.0, 1.0, n1)           # e[i] couples i and i+1 (last entry unused)
    d = np.abs(e) + np.abs(np.roll(e, 1)) + rng.uniform(1e-3, 2.0, n1)   # SPD by dominance
    d[0] = abs(e[0]) + 0.5
    A = np.diag(d) + np.diag(e[:-1], 1) + np.diag(e[:-1], -1)
    b = rng.standard_normal(n1)
    cp, x = np.zeros(n1), np.zeros(n1)
    sym_tridiag_solve(d, e, b, x, cp)
    np.testing.assert_allclose(A @ x, b, rtol=0, atol=1e-12 * np.abs(b).max())
    y = b.copy()
    sym_tridiag_solve(d, e, y, y, cp)           # in place
    np.testing.assert_array_equal(y, x)


def test_stiff_and_mass_scaled_rows():
    """The Newton matrices mix masses ~1e-3 with stiffnesses ~1e8 (contact rows)."""
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
    A = np.diag(dd) + np.diag(e[:-1], 1) + np.diag(e[:-1], -1)
    b = np.linspace(-1, 1, n1)
    cp, x = np.zeros(n1), np.zeros(n1)
    sym_tridiag_solve(dd, e, b, x, cp)
    np.testing.assert_allclose(x, np.linalg.solve(A, b), rtol=1e-8)
