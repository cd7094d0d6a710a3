"""O(N) banded solves used by the implicit sub-steps: symmetric tri- and pentadiagonal.

Compiled without fused multiply-adds: the pivots' rounding errors must cancel as they do
unfused (``rodjit._jit``)."""
from .._jit import exact_kernel, exact_step_kernel, step_kernel


@exact_kernel
def tridiag_factor(d, off, cp, inv):
    """Thomas factorisation of the symmetric tridiagonal matrix (diag ``d``, constant
    off-diagonal ``off``); fills ``cp`` (modified super-diagonal) and ``inv`` (1/pivots)."""
    n1 = d.size
    inv[0] = 1.0 / d[0]
    cp[0] = off * inv[0]
    for i in range(1, n1):
        inv[i] = 1.0 / (d[i] - off * cp[i - 1])
        cp[i] = off * inv[i]


@exact_step_kernel
def tridiag_solve(off, cp, inv, rhs, x):
    """Solve with a ``tridiag_factor`` result; ``x`` may alias ``rhs``."""
    n1 = rhs.size
    x[0] = rhs[0] * inv[0]
    for i in range(1, n1):
        x[i] = (rhs[i] - off * x[i - 1]) * inv[i]
    for i in range(n1 - 2, -1, -1):
        x[i] -= cp[i] * x[i + 1]


@exact_kernel
def penta_factor(a0, a1, a2, l1, l2, dinv):
    """LDLᵀ of the symmetric pentadiagonal matrix with diagonals a0 (i,i), a1 (i,i+1),
    a2 (i,i+2).  Fills the unit-lower factor's sub-diagonals l1 (i,i-1), l2 (i,i-2) and
    1/D.  The matrices here are SPD (mass plus a PSD operator), so no pivoting."""
    n1 = a0.size
    d_m2 = 0.0
    d_m1 = 0.0
    for i in range(n1):
        li2 = 0.0
        li1 = 0.0
        if i >= 2:
            li2 = a2[i - 2] / d_m2
        if i >= 1:
            prev_l1 = l1[i - 1] if i >= 2 else 0.0
            li1 = (a1[i - 1] - li2 * d_m2 * prev_l1) / d_m1
        di = a0[i] - li1 * li1 * d_m1 - li2 * li2 * d_m2
        l1[i] = li1
        l2[i] = li2
        dinv[i] = 1.0 / di
        d_m2 = d_m1
        d_m1 = di


@exact_kernel
def penta_solve(l1, l2, dinv, rhs, x):
    """Solve with a ``penta_factor`` result; ``x`` may alias ``rhs``."""
    n1 = rhs.size
    for i in range(n1):
        z = rhs[i]
        if i >= 1:
            z -= l1[i] * x[i - 1]
        if i >= 2:
            z -= l2[i] * x[i - 2]
        x[i] = z
    for i in range(n1):
        x[i] *= dinv[i]
    for i in range(n1 - 1, -1, -1):
        z = x[i]
        if i + 1 < n1:
            z -= l1[i + 1] * x[i + 1]
        if i + 2 < n1:
            z -= l2[i + 2] * x[i + 2]
        x[i] = z


@exact_step_kernel
def sym_tridiag_solve(d, e, rhs, x, cp, pinv):
    """Solve the symmetric tridiagonal system with diagonal ``d`` and off-diagonal ``e``
    (e[i] is entry (i, i+1)), leaving its factor in ``cp`` (eliminated couplings) and
    ``pinv`` (reciprocal pivots) for more right-hand sides (``sym_tridiag_apply``); ``x``
    may alias ``rhs``.  For SPD matrices (the Newton Jacobians of the energy step, rebuilt
    at every iterate), so no pivoting.

    A twisted factorisation: Thomas eliminations from both ends at once, meeting at the
    middle row k (one division per row, as one sweep, but two independent recurrences of
    half the length: each row waits for the division of the row before it), then the
    substitution outward from row k.  Every pivot of an SPD matrix is positive, from either
    end.  The right-hand side is eliminated in the factor's pass (the eliminations of
    ``sym_tridiag_apply``): the ``energy`` step's Newton iterations mostly solve once with
    each factor, so a factor pass followed by an apply pass would read the arrays twice."""
    n1 = d.size
    n = n1 - 1
    k = n1 // 2
    # rows 0 … k−1 downward (cp[i]: e[i]/pivot) and rows n … k+1 upward (cp[i]: e[i−1]/pivot)
    if k >= 1:
        pinv[0] = 1.0 / d[0]
        cp[0] = e[0] * pinv[0]
        x[0] = rhs[0] * pinv[0]
    if n >= k + 1:
        pinv[n] = 1.0 / d[n]
        cp[n] = e[n - 1] * pinv[n]
        x[n] = rhs[n] * pinv[n]
    for j in range(1, max(k, n - k)):
        i = j
        if i <= k - 1:
            pinv[i] = 1.0 / (d[i] - e[i - 1] * cp[i - 1])
            cp[i] = e[i] * pinv[i]
            x[i] = (rhs[i] - e[i - 1] * x[i - 1]) * pinv[i]
        i = n - j
        if i >= k + 1:
            pinv[i] = 1.0 / (d[i] - e[i] * cp[i + 1])
            cp[i] = e[i - 1] * pinv[i]
            x[i] = (rhs[i] - e[i] * x[i + 1]) * pinv[i]
    piv = d[k]
    z = rhs[k]
    if k >= 1:
        piv -= e[k - 1] * cp[k - 1]
        z -= e[k - 1] * x[k - 1]
    if n >= k + 1:
        piv -= e[k] * cp[k + 1]
        z -= e[k] * x[k + 1]
    pinv[k] = 1.0 / piv
    x[k] = z * pinv[k]
    _substitute(cp, x, k, n)


@exact_step_kernel
def sym_tridiag_apply(e, cp, pinv, rhs, x):
    """Solve again with the factor a ``sym_tridiag_solve`` left (same ``e``), for another
    right-hand side: its eliminations with the stored pivots, no division; ``x`` may alias
    ``rhs``."""
    n1 = rhs.size
    n = n1 - 1
    k = n1 // 2
    if k >= 1:
        x[0] = rhs[0] * pinv[0]
    if n >= k + 1:
        x[n] = rhs[n] * pinv[n]
    for j in range(1, max(k, n - k)):
        i = j
        if i <= k - 1:
            x[i] = (rhs[i] - e[i - 1] * x[i - 1]) * pinv[i]
        i = n - j
        if i >= k + 1:
            x[i] = (rhs[i] - e[i] * x[i + 1]) * pinv[i]
    z = rhs[k]
    if k >= 1:
        z -= e[k - 1] * x[k - 1]
    if n >= k + 1:
        z -= e[k] * x[k + 1]
    x[k] = z * pinv[k]
    _substitute(cp, x, k, n)


@exact_step_kernel
def _substitute(cp, x, k, n):
    """The substitution outward from the middle row k of the twisted factorisation."""
    for j in range(1, max(k, n - k) + 1):
        i = k - j
        if i >= 0:
            x[i] -= cp[i] * x[i + 1]
        i = k + j
        if i <= n:
            x[i] -= cp[i] * x[i - 1]


# assembly, not a solve: compiled like the matrices it adds to (``step_kernel``)
@step_kernel
def add_bending(a0, a1, a2, w, n):
    """Add w·h³·B to the diagonals a0, a1, a2 of a symmetric pentadiagonal matrix: the
    bands of B = h CᵀC, C the curvature rows (1, −2, 1)/h² of nodes 1..N−1."""
    for i in range(1, n):
        a0[i - 1] += w
        a0[i] += 4.0 * w
        a0[i + 1] += w
        a1[i - 1] -= 2.0 * w
        a1[i] -= 2.0 * w
        a2[i - 1] += w
