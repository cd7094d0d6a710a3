"""The speed-motivated kernel paths compute exactly what the plain formulas compute.

(benchmarks/ measures the speed; these tests pin the numbers.)
"""
import math

import numba
import numpy as np
import pytest

import rodjit
from rodjit import _jit
from rodjit._jit import kernel
from rodjit.kernels.forces import BAD_STRAIN, NON_FINITE, OK, accel, momentum
from rodjit.kernels.reduce import nan_max, nan_min
from rodjit.model.laws import AikiKosugiFloor, AikiKosugiRod, Law, aiki_kosugi, register
from rodjit.model.system import RodSystem, masses
from rodjit.stepping import workspace as W
from rodjit.stepping.viscous import viscous_cn, viscous_sdirk2

ROD = AikiKosugiRod(100.0)
FLOOR = AikiKosugiFloor(1000.0, 0.05)


@kernel
def _minmax(x):
    lo = np.inf
    hi = -np.inf
    for i in range(x.size):
        lo = nan_min(lo, x[i])
        hi = nan_max(hi, x[i])
    return lo, hi


@pytest.mark.parametrize("n", [1, 5, 64, 1001])
def test_nan_min_max_reductions(rng, n):
    x = rng.normal(size=n)
    assert _minmax(x) == (x.min(), x.max())
    assert _minmax.py_func(x) == (x.min(), x.max())
    x[n // 2] = np.nan                       # NaN anywhere shows in both results
    assert all(math.isnan(r) for r in _minmax(x))
    assert all(math.isnan(r) for r in _minmax.py_func(x))
    assert nan_min(-0.0, 0.0) == 0.0 and math.copysign(1.0, nan_min(0.0, -0.0)) < 0


def test_momentum_is_the_mass_weighted_sum(rng):
    for n in (1, 2, 3, 4, 5, 6, 7, 8, 100, 1001):
        v = rng.normal(size=n + 1)
        exact = math.fsum(masses(n) * v)
        assert momentum(v, 1.0 / n) == pytest.approx(exact, rel=1e-14, abs=1e-15)
        # the plain-Python order to rounding (compiled, the last product may be fused)
        assert momentum(v, 1.0 / n) == pytest.approx(momentum.py_func(v, 1.0 / n),
                                                     rel=4e-16, abs=1e-16)


def _per_segment_bound(u, h):
    """The stiffness bound as the plain per-segment formula: 4 max f'(ε_i)/h²."""
    ih = 1.0 / h
    eps = (u[1:] - u[:-1]) * ih - 1.0
    return 4.0 * max(0.0, max(aiki_kosugi.rod_deriv(e, ROD) for e in eps)) * ih * ih


@pytest.mark.parametrize("n", [1, 2, 9, 200])
def test_stiffness_bound_from_the_strain_range_is_bitwise_the_per_segment_max(rng, n):
    system = RodSystem(n, 1.0 / n, 0.0, 0.0, -9.81)
    work = np.zeros((3, n + 1))
    for _ in range(20):
        eps = rng.uniform(-0.9, 2.0, n)
        u = 0.3 + np.concatenate([[0.0], np.cumsum((1 + eps) / n)])
        status, _, _, _, om2 = accel(u, work[2], work[0], work[1], system, ROD, FLOOR, True)
        assert status == OK
        assert om2 == _per_segment_bound(u, system.h)   # the floor is not touched: fd = 0


class ScanRod(AikiKosugiRod):
    """The Aiki–Kosugi rod again, registered without ``deriv_max``: the kernels scan."""


_SCAN = register(Law(name="aiki-kosugi-scan", kind="rod", params=ScanRod,
                     from_config=lambda rod: ScanRod(float(rod.kappa)),
                     value=aiki_kosugi.rod_value, deriv=aiki_kosugi.rod_deriv,
                     primitive=aiki_kosugi.rod_primitive, lower=aiki_kosugi.rod_lower))


@pytest.mark.slow
@pytest.mark.parametrize("integrator", ["verlet", "semi-implicit"])
def test_a_law_without_deriv_max_gives_the_same_run(integrator):
    """The scan and ``deriv_max`` give the same bound (bitwise, above); inlined into two
    different loops their strains may round differently (fused multiply-adds, rodjit._jit),
    so the runs agree to rounding: the same steps, states and step sizes to 1e-12 (a
    bound off by more than rounding would move them by far more)."""
    cfg = rodjit.Config().override({"rod.N": 12, "time.t_end": 1.5, "rod.mu": 0.5,
                                    "time.integrator": integrator})
    a = rodjit.simulate(cfg)
    b = rodjit.simulate(cfg.override({"rod.law": "aiki-kosugi-scan"}))
    assert a.stats["steps"] == b.stats["steps"] and a.n_bounces == b.n_bounces >= 1
    np.testing.assert_allclose(b.u_final, a.u_final, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(b.v_final, a.v_final, rtol=0, atol=1e-10)
    np.testing.assert_allclose(b.diagnostics["dt"], a.diagnostics["dt"], rtol=1e-9)


@pytest.mark.parametrize("u0", [0.3, -0.01])
def test_acceleration_without_the_stiffness_bound_is_the_same(rng, u0):
    """``accel(bound=False)`` (the energy step) fills the same accelerations and stresses
    and reports the same status, strain and floor force; only the bound is left out."""
    n = 12
    system = RodSystem(n, 1.0 / n, 1e-3, 0.0, -9.81)
    u = u0 + np.linspace(0.0, 1.0, n + 1) + 1e-3 * rng.normal(size=n + 1)
    out = {}
    for bound in (True, False):
        work = np.zeros((3, n + 1))
        res = accel(u, work[2], work[0], work[1], system, ROD, FLOOR, True, bound)
        out[bound] = (res, work)
    (r1, w1), (r0, w0) = out[True], out[False]
    assert r1[:4] == r0[:4] and r1[0] == OK and np.array_equal(w1, w0)
    assert r1[4] > 0.0 and r0[4] == 0.0


def test_exact_compression_limit_is_flagged_not_raised():
    """ε = −1 exactly divides by zero in f: IEEE inf/nan (error_model="numpy"), which the
    admissibility test reports, never a ZeroDivisionError inside the loop."""
    n = 4
    system = RodSystem(n, 0.25, 0.0, 0.0, -9.81)
    work = np.zeros((3, n + 1))
    u = np.array([0.5, 0.75, 0.75, 1.0, 1.25])
    assert accel(u, work[2], work[0], work[1], system, ROD, FLOOR, True)[0] == BAD_STRAIN
    u = np.array([0.5, 0.75, np.inf, 1.0, 1.25])
    assert accel(u, work[2], work[0], work[1], system, ROD, FLOOR, True)[0] == NON_FINITE


@kernel
def _weighted_sum(x, y):
    """A kernel that is not inlined: its callers hand it arrays."""
    s = 0.0
    for i in range(x.size):
        s += x[i] * (i + 1) + y[i]
    return s


def _alternating_views(state, trial, work, steps):
    """The time loop's pattern: rows of whichever array holds the current state, handed
    to a kernel that is not inlined, and a write through a view."""
    e = 0.0
    for j in range(steps):
        cur = state if j % 2 == 0 else trial
        e += _weighted_sum(cur[0], cur[1])
        row = work[2]
        row[j] = e
    return e


@pytest.mark.skipif(not (_jit.load_numba() and _jit._CAN_DISABLE_NRT), reason="this Numba cannot disable reference counting")
def test_kernels_count_no_references(rng):
    """Compiled with rodjit's options (rodjit._jit), views and array arguments make no
    NRT_incref/NRT_decref calls, where Numba's defaults make them; the results and the
    writes through views are the same."""
    n = 4
    state = rng.normal(size=(3, n + 1))
    trial = rng.normal(size=(3, n + 1))
    want = [_weighted_sum(x[0], x[1]) for x in (state, trial, state)]
    ir = {}
    for name, opts in (("rodjit", {k: v for k, v in _jit.JIT_OPTIONS.items() if k != "cache"}),
                       ("default", {})):
        f = numba.njit(**opts)(_alternating_views)
        work = np.zeros((3, n + 1))
        e = f(state, trial, work, 3)
        assert e == sum(want) and np.array_equal(work[2, :3], np.cumsum(want))
        ir[name] = "".join(f.inspect_llvm().values())
    # Numba's defaults count references (LLVM may inline NRT_incref, whose body it has,
    # and keep the calls of NRT_decref, or the other way round, depending on the CPU)
    assert "call void @NRT_incref" in ir["default"] or "call void @NRT_decref" in ir["default"]
    assert "@NRT_incref" not in ir["rodjit"] and "@NRT_decref" not in ir["rodjit"]


@pytest.mark.parametrize("sub", [viscous_cn, viscous_sdirk2])
def test_a_reused_viscous_factorisation_gives_the_same_bits(rng, sub):
    n = 30
    system = RodSystem(n, 1.0 / n, 0.0, 3.0, 0.0)
    v = rng.normal(size=n + 1)
    fresh = np.zeros((W.WORK_ROWS, n + 1))
    warm = np.zeros((W.WORK_ROWS, n + 1))
    for tau in (1e-3, 1e-3, 2e-3, 1e-3):       # reuse, refactor, refactor back
        out_warm = np.empty(n + 1)
        dw = sub(v, out_warm, tau, system, warm)
        fresh[:] = 0.0
        out_fresh = np.empty(n + 1)
        df = sub(v, out_fresh, tau, system, fresh)
        assert np.array_equal(out_warm, out_fresh) and dw == df
