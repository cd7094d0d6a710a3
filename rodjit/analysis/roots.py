"""The root of an increasing function by bisection: the one search behind the observed order
of a ladder (``richardson.observed_order``) and Student's t quantile (``fit_table``)."""
from __future__ import annotations

from typing import Callable

__all__ = ["increasing_root"]


def increasing_root(f: Callable[[float], float], target: float, lo: float, hi: float,
                    rtol: float = 0.0, atol: float = 0.0, iterations: int = 200) -> float:
    """The x in [lo, hi] where the increasing ``f`` reaches ``target``, by bisection until
    the bracket is narrower than ``atol + rtol·hi`` (or to rounding: ``iterations``).

    Parameters
    ----------
    f : callable
        Increasing on [lo, hi], with f(lo) < target <= f(hi).
    target : float
        The value sought.
    lo, hi : float
        The bracket.
    rtol, atol : float
        The bracket's width at which the search stops.
    iterations : int
        The most halvings.

    Returns
    -------
    float
        The middle of the last bracket.
    """
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        if f(mid) < target:
            lo = mid
        else:
            hi = mid
        if hi - lo <= atol + rtol * hi:
            break
    return 0.5 * (lo + hi)
