"""Banded solvers against dense linear algebra."""
import numpy as np
import pytest

from rodjit.kernels.banded import penta_factor, penta_solve, tridiag_factor, tridiag_solve


@pytest.mark.parametrize("n1", [1, 2, 3, 4, 17])
def test_tridiagonal(rng, n1):
    off = -0.7
    d = rng.uniform(2.0, 3.0, n1)
    A = np.diag(d) + off * (np.eye(n1, k=1) + np.eye(n1, k=-1))
    b = rng.normal(size=n1)
    cp, inv, x = np.zeros(n1), np.zeros(n1), np.zeros(n1)
    tridiag_factor(d, off, cp, inv)
    tridiag_solve(off, cp, inv, b, x)
    assert np.allclose(A @ x, b, rtol=0, atol=1e-13)
    tridiag_solve(off, cp, inv, b, b)   # in place
    assert np.allclose(b, x, rtol=0, atol=1e-15)


@pytest.mark.parametrize("n1", [1, 2, 3, 5, 31])
def test_pentadiagonal_spd(rng, n1):
    R = rng.normal(size=(n1 + 2, n1))
    A = np.diag(rng.uniform(1, 2, n1)) + R.T @ R
    A = np.triu(np.tril(A, 2), -2)          # keep five bands
    A += np.diag(np.abs(A).sum(1))         # make it SPD
    a0, a1, a2 = np.diag(A).copy(), np.zeros(n1), np.zeros(n1)
    a1[:-1] = np.diag(A, 1)
    if n1 > 2:
        a2[:-2] = np.diag(A, 2)
    l1, l2, dinv, x = (np.zeros(n1) for _ in range(4))
    b = rng.normal(size=n1)
    penta_factor(a0, a1, a2, l1, l2, dinv)
    penta_solve(l1, l2, dinv, b, x)
    assert np.allclose(A @ x, b, rtol=0, atol=1e-12)
