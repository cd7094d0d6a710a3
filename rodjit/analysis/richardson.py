"""Observed order of convergence and Richardson extrapolation over a refinement ladder.

Levels ``h_0 > h_1 > ... > h_n`` (mesh width 1/N, or a time tolerance) with values
``f_k = f(h_k)``.  If ``f(h) = f* + C h^p + o(h^p)``, three consecutive levels give the
observed order from ``(f_{k} − f_{k+1}) / (f_{k+1} − f_{k+2}) = (h_k^p − h_{k+1}^p) /
(h_{k+1}^p − h_{k+2}^p)`` (``r^p`` for a constant ratio ``r``), and the finest pair the
extrapolated value ``f* ≈ f_n + (f_n − f_{n−1}) h_n^p / (h_{n−1}^p − h_n^p)``.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from .roots import increasing_root

__all__ = ["observed_order", "extrapolate", "Study", "study"]

P_MIN, P_MAX = 0.25, 8.0        # orders outside this range are not asymptotic behaviour
# Safety factors of the error bar (Roache's grid convergence index, Roache 1998,
# "Verification and Validation in Computational Science and Engineering", ch. 5): the
# Richardson correction |f* − f_n| estimates the error of the finest level only as well as
# the observed order holds.  With the order checked by a fourth level the bar is 1.25 times
# the correction (or the change of the extrapolation between the last two triples, if
# larger); with three levels, whose order nothing checks, 3 times, and as many times the
# last difference where no order fits (orders outside their range or scattering, or
# differences alternating: on a tolerance ladder the alternation is the step controller's
# noise, which does not put the limit between the last two levels).  Measured: a dp54
# tolerance ladder (rtol 1e-4, 2.5e-5, 6.25e-6; paper-mu0, t_end 1) alternates, and its
# contact time lies 6.7e-7 from dop853's at rtol 1e-12 where the last difference is 5.6e-7.
SAFETY_CHECKED = 1.25
SAFETY_UNCHECKED = 3.0
ORDER_SPREAD = 0.25             # consecutive orders closer than this fraction agree
EXACT = 1e-12                   # differences below this (relative) are rounding


def observed_order(h, f) -> float:
    """Order p from three levels (h coarse to fine); NaN if the differences do not shrink
    monotonically (no order fits)."""
    h1, h2, h3 = (float(x) for x in h)
    d1, d2 = f[0] - f[1], f[1] - f[2]
    if d1 == 0 or d2 == 0 or d1 * d2 < 0:
        return math.nan
    q = d1 / d2

    def ratio(p):
        return (h1 ** p - h2 ** p) / (h2 ** p - h3 ** p)

    lo, hi = 1e-3, 20.0           # ratio(p) increases in p for h1 > h2 > h3
    if not ratio(lo) < q < ratio(hi):
        return math.nan
    return increasing_root(ratio, q, lo, hi, atol=1e-12)


def extrapolate(h, f, p: float) -> float:
    """Richardson value from the last two levels with order p."""
    h1, h2 = float(h[-2]), float(h[-1])
    return float(f[-1] + (f[-1] - f[-2]) * h2 ** p / (h1 ** p - h2 ** p))


@dataclass
class Study:
    """One observable along a ladder.

    ``status``: ``converged`` (orders agree: extrapolated, error from the last two
    extrapolations or the Richardson correction times a safety factor), ``pre-asymptotic`` (differences shrink
    but orders scatter: extrapolated with a warning and a wider error), ``oscillating``
    (differences shrink but alternate: no extrapolation, the finest value with the last
    difference as error), ``not converging`` (differences do not shrink: nothing
    extrapolated), ``exact`` (all levels agree to rounding), ``undefined`` (a level has no
    finite value), ``no limit`` (set by ``converge``: the model has no continuum limit
    along this ladder, so nothing is extrapolated and no error is given)."""

    name: str
    h: list
    values: list
    orders: list = field(default_factory=list)
    order: float = math.nan
    extrapolated: float = math.nan
    error: float = math.nan
    status: str = "undefined"
    message: str = ""

    def to_dict(self) -> dict:
        return asdict(self)


def study(name: str, h, values) -> Study:
    """Orders, extrapolation and error estimate of ``values`` at levels ``h`` (coarse to
    fine, at least three for an order)."""
    h = [float(x) for x in h]
    f = [float(x) for x in values]
    s = Study(name, h, f)
    if all(x == f[0] for x in f) and not math.isnan(f[0]):
        # the same at every level, also ±inf (a contact that never ends at any level)
        s.status, s.extrapolated, s.error, s.order = "exact", f[0], 0.0, math.inf
        s.message = "every level gives the same value"
        return s
    if any(not math.isfinite(x) for x in f):
        bad = [hh for hh, x in zip(h, f) if not math.isfinite(x)]
        s.message = f"no finite value at h = {', '.join(f'{x:g}' for x in bad)}"
        return s
    if len(f) < 3:
        s.status, s.extrapolated = "too few levels", f[-1]
        s.error = abs(f[-1] - f[-2]) if len(f) == 2 else math.nan
        s.message = "an order needs three levels"
        return s
    scale = max(abs(x) for x in f) or 1.0
    d = np.diff(f)
    if np.all(np.abs(d) <= EXACT * scale):
        s.status, s.extrapolated, s.error, s.order = "exact", f[-1], 0.0, math.inf
        s.message = "every level gives the same value"
        return s
    s.orders = [observed_order(h[k:k + 3], f[k:k + 3]) for k in range(len(f) - 2)]
    last = abs(d[-1])
    if abs(d[-1]) >= abs(d[-2]):
        s.status = "not converging"
        s.message = (f"the values do not settle: the last differences "
                     f"{d[-2]:.3g}, {d[-1]:.3g} do not shrink")
        s.extrapolated, s.error = math.nan, math.inf
        return s
    if d[-1] * d[-2] < 0:
        s.status = "oscillating"
        s.message = "differences shrink but alternate in sign: finest value, no extrapolation"
        s.extrapolated, s.error = f[-1], SAFETY_UNCHECKED * last
        return s
    p = s.orders[-1]
    s.order = p
    if not (P_MIN <= p <= P_MAX):
        s.status = "pre-asymptotic"
        s.message = f"observed order {p:.3g} outside [{P_MIN}, {P_MAX}]: finest value"
        s.extrapolated, s.error = f[-1], SAFETY_UNCHECKED * last
        return s
    s.extrapolated = extrapolate(h, f, p)
    correction = abs(s.extrapolated - f[-1])
    agree = (len(s.orders) >= 2 and math.isfinite(s.orders[-2])
             and abs(s.orders[-1] - s.orders[-2]) <= ORDER_SPREAD * abs(s.orders[-1]))
    if len(s.orders) >= 2 and not agree:
        s.status = "pre-asymptotic"
        s.message = (f"orders scatter ({', '.join(f'{x:.3g}' for x in s.orders)}): the "
                     f"ladder is not in the asymptotic range; refine further")
        s.error = SAFETY_UNCHECKED * max(correction, last)
        return s
    s.status = "converged"
    if len(s.orders) >= 2:
        prev = extrapolate(h[:-1], f[:-1], s.orders[-2])
        s.error = max(abs(s.extrapolated - prev), SAFETY_CHECKED * correction)
        s.message = f"order {p:.3g}"
    else:
        s.error = SAFETY_UNCHECKED * correction    # three levels: nothing checks the order
        s.message = f"order {p:.3g} from three levels (not checked: add a level)"
    return s
