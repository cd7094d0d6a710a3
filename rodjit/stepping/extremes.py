"""The extremes of a bounce between the step points: the smallest bottom height u_0, the
largest floor force σ_b(u_0) and the smallest segment strain over an accepted step.

A bounce's ``min_u0``, ``max_floor_force`` and ``min_strain`` taken at the step points only
miss what happens inside a step: a coarse step over the deepest point of an impact reports
a penetration and a force from wherever the steps happen to fall, and a convergence study
then sees the step points move, not the extreme.  So over every step the loop tracks
(a bounce open, or the step ending in contact) the state inside the step comes from

- the scheme's dense output (``schemes.dense``: ``dp54``, ``dop853``, ``radau5``), of the
  scheme's own order inside the step;
- for the others (``verlet``, ``semi-implicit``, ``energy``), the cubic Hermite
  interpolant of (u, v) at the step's two ends, third order in dt, exact for the motion of
  constant jerk.

Each quantity is searched for its extreme inside the step: sampled at θ = k/``SAMPLES``,
then refined by golden-section search over the two sample intervals around the best
sample (``REFINE`` iterations, the bracket shrinks to 0.618^REFINE of its width).  The
step's end values always count, so an extreme is never less extreme than at the step
points; the floor force is the law's ``value`` at the interpolated u_0 (as the diagnostics'
``floor_force``), its largest value over the samples and the refined minimum of u_0.

A step that runs one way in u_0 and in every segment's length (ordered Bernstein
coefficients of the cubic Hermite, ``monotone``: a settling rod creeping towards its rest
state) has the extremes of u_0 and of the strain at its ends, which are taken without a
search; its floor force is taken at the same samples as a searched step's, since a law's
force need not be largest at the deepest point (taking it at the step's ends only would be
5 % faster, and wrong for such a law).  Searching those steps too makes the loop 1.82×
slower (CPU time per step on 16 points of the paper-mu100 μ × κ_b × β grid, most of whose
steps lie in an open bounce: 824 against 452 ns).
"""
from ..model.laws import value
from .schemes import dense, has_dense
from .._jit import step_kernel

__all__ = ["SAMPLES", "REFINE", "state_at", "step_extremes", "search_extremes", "monotone"]

SAMPLES = 8      # samples per step (θ = k/SAMPLES)
REFINE = 16      # golden-section iterations per quantity (the bracket to 5e-4 of its width)
_GOLD = 0.6180339887498949


@step_kernel
def state_at(scheme, old, new, work, interp, dt, theta):
    """(u, v) of the step from ``old`` to ``new`` (rows u, v, a) at t + θ dt into ``interp``:
    the scheme's dense output, or the cubic Hermite of the step's ends (module docstring)."""
    if has_dense(scheme):
        dense(scheme, old[0], old[1], old[2], new[0], new[1], new[2], work, dt, theta,
              interp[0], interp[1])
    else:
        uo = interp[0]
        for i in range(uo.size):
            uo[i] = _hermite(old, new, dt, theta, i)


@step_kernel
def _hermite(old, new, dt, theta, i):
    """Node i's height at t + θ dt on the cubic Hermite of the step's ends."""
    s = theta
    h00 = (1.0 + 2.0 * s) * (1.0 - s) * (1.0 - s)
    h10 = s * (1.0 - s) * (1.0 - s) * dt
    h01 = s * s * (3.0 - 2.0 * s)
    h11 = s * s * (s - 1.0) * dt
    return h00 * old[0][i] + h10 * old[1][i] + h01 * new[0][i] + h11 * new[1][i]


@step_kernel
def _min_strain(u, h):
    e = (u[1] - u[0]) / h - 1.0
    for i in range(1, u.size - 1):
        e = min(e, (u[i + 1] - u[i]) / h - 1.0)
    return e


@step_kernel
def _quantity(scheme, old, new, work, interp, h, dt, theta, which):
    """u_0 (``which`` 0) or the smallest strain (1) inside the step at θ."""
    if which == 0 and not has_dense(scheme):
        return _hermite(old, new, dt, theta, int(0))    # the bottom node alone
    state_at(scheme, old, new, work, interp, dt, theta)
    if which == 0:
        return interp[0][0]
    return _min_strain(interp[0], h)


@step_kernel
def _golden_min(scheme, old, new, work, interp, h, dt, lo, hi, which, best):
    """The smallest value of the quantity on [lo, hi] found by golden-section search, or
    ``best`` if that is smaller."""
    x1 = hi - _GOLD * (hi - lo)
    x2 = lo + _GOLD * (hi - lo)
    f1 = _quantity(scheme, old, new, work, interp, h, dt, x1, which)
    f2 = _quantity(scheme, old, new, work, interp, h, dt, x2, which)
    for _ in range(REFINE):
        if f1 <= f2:
            hi = x2
            x2 = x1
            f2 = f1
            x1 = hi - _GOLD * (hi - lo)
            f1 = _quantity(scheme, old, new, work, interp, h, dt, x1, which)
        else:
            lo = x1
            x1 = x2
            f1 = f2
            x2 = lo + _GOLD * (hi - lo)
            f2 = _quantity(scheme, old, new, work, interp, h, dt, x2, which)
    return min(best, f1, f2)


@step_kernel
def step_extremes(scheme, old, new, work, interp, system, floor, dt, ff_end, emin_end):
    """``(min u_0, max floor force, min strain)`` over the step of length dt from ``old``
    to ``new`` (its end values ``ff_end``, ``emin_end`` included); for a scheme with a dense
    output its ``dense_setup`` has run for the step.  ``interp`` (2 rows) is scratch.
    A step that runs one way in u_0 and every segment's length (``monotone``) is not
    searched."""
    if monotone(scheme, old, new, dt):
        # u_0 and every segment's length run one way over the step: their extremes are
        # at the step's ends (the search would find them, up to its rounding); the force,
        # whose law may peak anywhere, at the search's samples
        u_best = min(old[0][0], new[0][0])
        ff = max(ff_end, value(u_best, floor))
        for k in range(1, SAMPLES):
            ff = max(ff, value(_hermite(old, new, dt, k / SAMPLES, int(0)), floor))
        return u_best, ff, min(emin_end, _min_strain(old[0], system.h))
    return search_extremes(scheme, old, new, work, interp, system, floor, dt, ff_end,
                           emin_end)


@step_kernel
def search_extremes(scheme, old, new, work, interp, system, floor, dt, ff_end, emin_end):
    """``step_extremes`` by sampling and golden-section search (module docstring), for
    any step."""
    h = system.h
    u_best = min(old[0][0], new[0][0])
    e_best = emin_end
    ff = ff_end
    ku = 0 if old[0][0] <= new[0][0] else SAMPLES
    ke = SAMPLES
    for k in range(1, SAMPLES):
        theta = k / SAMPLES
        state_at(scheme, old, new, work, interp, dt, theta)
        u0 = interp[0][0]
        ff = max(ff, value(u0, floor))
        if u0 < u_best:
            u_best = u0
            ku = k
        e = _min_strain(interp[0], h)
        if e < e_best:
            e_best = e
            ke = k
    lo = max(ku - 1, 0) / SAMPLES
    hi = min(ku + 1, SAMPLES) / SAMPLES
    u_best = _golden_min(scheme, old, new, work, interp, h, dt, lo, hi, int(0), u_best)
    ff = max(ff, value(u_best, floor))
    lo = max(ke - 1, 0) / SAMPLES
    hi = min(ke + 1, SAMPLES) / SAMPLES
    e_best = _golden_min(scheme, old, new, work, interp, h, dt, lo, hi, int(1), e_best)
    return u_best, ff, e_best


@step_kernel
def _ordered(b0, b1, b2, b3):
    """Whether Bernstein coefficients are in order, so their cubic is monotone on [0, 1]."""
    return (b0 <= b1 <= b2 <= b3) or (b0 >= b1 >= b2 >= b3)


@step_kernel
def monotone(scheme, old, new, dt):
    """Whether the cubic Hermite of the step runs one way in u_0 and in every segment's
    length (ordered Bernstein coefficients), so that u_0's and the strain's extremes over
    the step are at its ends.  False for a scheme with a dense output."""
    if has_dense(scheme):
        return False
    ua, va, ub, vb = old[0], old[1], new[0], new[1]
    d = dt / 3.0
    if not _ordered(ua[0], ua[0] + d * va[0], ub[0] - d * vb[0], ub[0]):
        return False
    for i in range(ua.size - 1):
        a0 = ua[i + 1] - ua[i]
        a3 = ub[i + 1] - ub[i]
        if not _ordered(a0, a0 + d * (va[i + 1] - va[i]), a3 - d * (vb[i + 1] - vb[i]), a3):
            return False
    return True
